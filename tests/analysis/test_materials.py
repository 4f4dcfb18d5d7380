"""The plausibility table of the published fits: its numbers come back from the
public API, and the checker fails on models that are broken on purpose."""

import math

import numpy as np
import pytest

import plausible
from plausible.integrals.albedo import direction
from plausible.analysis.materials import check_fit, check_model, markdown, summary
from plausible.models.sum import Sum


#: A short grid keeps the tests fast (the table uses THETAS_DEG).
GRID = (0.0, 60.0, 89.9)


@pytest.fixture(scope="module")
def row():
    return check_fit("nickel", "ngan2005/ward-duer", thetas_deg=GRID)


def test_the_rows_largest_albedo_is_plausible_albedo_of_the_material(row):
    m = plausible.material("nickel", "ngan2005/ward-duer")
    a = plausible.albedo(m, direction(math.radians(row.theta_deg), 0.0))
    k = "RGB".index(row.channel)
    assert row.max_albedo == pytest.approx(float(a.value[k]), abs=2e-4)
    # and it is the largest over the grid and the channels
    others = [np.max(plausible.albedo(m, direction(math.radians(t), 0.0)).value) for t in (0.0, 60.0)]
    assert max(others) <= row.max_albedo + 1e-9


def test_the_rows_asymmetry_is_plausible_reciprocity(row):
    assert row.asymmetry == plausible.reciprocity(plausible.material("nickel", "ngan2005/ward-duer")).figure
    assert row.reciprocal and row.thetas_deg == GRID


def test_a_model_that_gains_energy_is_flagged_with_where():
    # Ward-Dür's 1 / (cos_i cos_o) grows without bound toward grazing incidence
    r = check_model(Sum([plausible.make("ward", alpha_x=0.3, alpha_y=0.3, rs=1.0, variant="duer")]), "w", "test", GRID)
    assert r.gains_energy and r.max_albedo > 1.5 and r.theta_deg == max(GRID)
    assert "yes, +" in markdown([r])


def test_a_non_reciprocal_part_is_flagged():
    r = check_model(Sum([plausible.make("lambertian", rd=0.2), plausible.make("phong", ks=0.5, n=10)]), "p", "test", GRID)
    assert not r.reciprocal and r.asymmetry > 1e-3
    assert "| NO (" in markdown([r])


def test_a_plausible_material_passes_and_the_summary_counts_it(row):
    ok = check_fit("nickel", "ngan2005/ashikhmin-shirley", thetas_deg=GRID)
    assert ok.reciprocal and not ok.gains_energy
    s = summary([row, ok])
    assert [x["n"] for x in s] == [1, 1]


def test_a_diffuse_part_takes_its_closed_form_and_agrees_with_the_quadrature():
    """The Lambertian part of a fit is not integrated: its declared albedo (``rd``)
    is used, which the quadrature of ``f cos`` confirms at every angle of the grid;
    a part with a glossy lobe has no closed form and is integrated."""
    from plausible.analysis.materials import THETAS_DEG, closed_form_albedo

    m = plausible.material("nickel", "ngan2005/ward")
    lam, ward = m.parts
    exact = closed_form_albedo(lam)
    assert exact is not None and closed_form_albedo(ward) is None
    for t in THETAS_DEG:
        wi = direction(math.radians(t), 0.0)
        got, ref = exact(wi), plausible.albedo(lam, wi)
        np.testing.assert_allclose(got.value, ref.value, rtol=0, atol=1e-6)
        np.testing.assert_array_equal(got.value, np.asarray(lam.params["rd"], dtype=np.float64))
    assert np.all(exact(np.array([0.6, 0.0, -0.8])).value == 0.0)


def test_the_tables_are_written_whole_and_an_interrupt_leaves_the_docs_as_they_were(row, tmp_path, monkeypatch):
    """write_tables writes materials-table.md and .csv, and the summary between the markers
    of an existing materials.md (the user's own text around them kept); Ctrl-C while the
    files are being replaced leaves every file as it was and no temporary file behind."""
    import csv

    import plausible.text
    from plausible.analysis.materials import BEGIN, END, write_tables

    doc = tmp_path / "materials.md"
    doc.write_text(f"my notes\n{BEGIN}\nold\n{END}\nmore notes\n")
    written = write_tables([row], tmp_path)
    assert {p.name for p in written} == {"materials-table.md", "materials-table.csv", "materials.md"}
    text = doc.read_text()
    assert text.startswith(f"my notes\n{BEGIN}\n") and text.endswith(f"{END}\nmore notes\n") and "old" not in text
    rows = list(csv.reader((tmp_path / "materials-table.csv").open(newline="")))
    assert rows[1][:2] == ["nickel", "ngan2005/ward-duer"] and float(rows[1][3]) == pytest.approx(row.max_albedo)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(plausible.text.os, "replace", interrupted)
    other = check_model(Sum([plausible.make("lambertian", rd=0.5)]), "grey", "test", GRID)
    with pytest.raises(KeyboardInterrupt):
        write_tables([other], tmp_path)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_a_full_disk_at_the_csv_leaves_neither_table(row, tmp_path, disk_full_at):
    """Issue 45: the table and its CSV are written all or none; a disk that fills while
    the CSV is written (ENOSPC, simulated) leaves the old files as they were and no
    table without its CSV, and the error names the file asked for."""
    import errno

    from plausible.analysis.materials import write_tables

    disk_full_at("materials-table.csv")
    with pytest.raises(OSError) as e:
        write_tables([row], tmp_path)
    assert e.value.errno == errno.ENOSPC and e.value.filename == str(tmp_path / "materials-table.csv")
    assert list(tmp_path.iterdir()) == []
