"""Issue 45, items 3, 4 and 8: a file or folder that cannot be read or written (read-only,
full, no permission) ends a command with exit 2 and one line naming it, checked before the
work where the command can; no partial or misplaced output; small input mistakes refused
with the option named.

A full disk is a 64 KiB tmpfs filled up, a read-only one a tmpfs mounted ``ro`` (both need
root and ``mount``: skipped elsewhere); the unreadable file needs an unprivileged user
(``setpriv``, as root)."""

import errno
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import plausible
from plausible.cli import main


def run(*args, **kw):
    return CliRunner().invoke(main, [str(a) for a in args], terminal_width=400, **kw)


def _mount(path, *opts):
    path.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("needs root and mount for a tmpfs")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", ",".join(("size=64k",) + opts), "tmpfs", str(path)],
                       capture_output=True)
    if r.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")


@pytest.fixture
def full_disk(tmp_path):
    """A folder on a 64 KiB filesystem with no space left."""
    d = tmp_path / "full"
    _mount(d)
    try:
        with open(d / "filler", "wb") as f:
            while True:
                f.write(b"\0" * 4096)
                f.flush()
    except OSError as e:
        assert e.errno == errno.ENOSPC
    yield d
    subprocess.run(["umount", str(d)])


@pytest.fixture
def read_only(tmp_path):
    """A folder on a read-only filesystem."""
    d = tmp_path / "ro"
    _mount(d, "ro")
    yield d
    subprocess.run(["umount", str(d)])


def _refused(r, *words):
    """Exit 2, no traceback, one message naming each of ``words``."""
    assert r.exit_code == 2, r.output
    assert isinstance(r.exception, SystemExit), r.exception
    assert "Traceback" not in r.output
    for w in words:
        assert w in r.output, (w, r.output)


def _never(*a, **kw):
    raise AssertionError("the work started before the output was checked")


# -- item 3: every read or write failure a clear exit 2 ----------------------------------

def test_albedo_plot_on_a_full_disk_exits_2_naming_the_file_and_leaves_no_empty_png(full_disk):
    r = run("albedo", "lambertian", "-n", "2", "--plot", full_disk / "a.png")
    _refused(r, str(full_disk / "a.png"), "No space left on device")
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]      # no 0-byte a.png, no temporary file


def test_check_materials_out_on_a_read_only_disk_is_refused_before_the_work(read_only, monkeypatch):
    import plausible.analysis.materials as M

    monkeypatch.setattr(M, "check_fits", _never)
    monkeypatch.setattr(M, "work_list", lambda fits=None, names=None: [("alum-bronze", "ngan2005/ward")])
    r = run("check", "--materials", "--quick", "--out", read_only / "tables")   # the whole table (a one-fit stand-in)
    _refused(r, "--out", "Read-only file system")


def test_check_materials_out_on_a_full_disk_exits_2_and_writes_neither_table(tmp_path, disk_full_at, monkeypatch):
    """The disk fills while the CSV is written (ENOSPC simulated there): exit 2 naming it, and
    materials-table.md is not left without its CSV."""
    import plausible.analysis.materials as M

    monkeypatch.setattr(M, "work_list", lambda fits=None, names=None: [("alum-bronze", "ngan2005/ward")])
    disk_full_at("materials-table.csv")
    r = run("check", "--materials", "--quick", "--out", tmp_path, "--jobs", "1")
    # the rows checked are kept in the run's journal (the batch engine: a rerun resumes), the tables not written
    _refused(r, "--out", "No space left on device")
    assert not {"materials-table.md", "materials-table.csv"} & {p.name for p in tmp_path.iterdir()}
    assert (tmp_path / ".materials-rows.jsonl").exists()


def test_convert_table_out_and_markdown_on_a_read_only_disk_are_refused_before_the_work(read_only, tmp_path,
                                                                                         monkeypatch):
    from plausible.conversion import table

    monkeypatch.setattr(table, "run_table", _never)
    _refused(run("convert-table", "--out", read_only / "rows.jsonl", "--limit", "1"), "--out",
             "Read-only file system")
    _refused(run("convert-table", "--out", tmp_path / "rows.jsonl", "--markdown", read_only / "t.md",
                 "--limit", "1"), "--markdown", "Read-only file system")
    assert not (tmp_path / "rows.jsonl").exists()


def test_an_oserror_of_any_command_is_exit_2_with_the_path_and_reason(monkeypatch):
    """The one mapping in the command group: an OSError that reaches it (here a target on an
    unreadable disk, simulated in the fitter) is one line and status 2."""
    import plausible.fitting

    def unreadable(*a, **kw):
        raise OSError(errno.EIO, "Input/output error", "/mnt/target.binary")

    monkeypatch.setattr(plausible.fitting, "fit", unreadable)
    _refused(run("fit", "lambertian", "--target", "/mnt/target.binary"), "/mnt/target.binary", "Input/output error")


@pytest.mark.skipif(os.name != "posix" or not hasattr(os, "geteuid") or os.geteuid() != 0
                    or shutil.which("setpriv") is None, reason="needs root and setpriv to run as nobody")
def test_fit_target_that_cannot_be_read_exits_2_naming_it():
    import tempfile

    home = Path(tempfile.mkdtemp())     # pytest's tmp_path is closed to other users
    try:
        home.chmod(0o755)
        target = home / "target.csv"
        target.write_text("0,0,1,0,0,1,0.3\n")
        target.chmod(0)
        src = Path(plausible.__file__).resolve().parents[1]
        r = subprocess.run(["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups", sys.executable, "-c",
                            "import sys; sys.path.insert(0, sys.argv[1]); from plausible.cli import main; "
                            "main(sys.argv[2:])", str(src), "fit", "lambertian", "--target", str(target)],
                           capture_output=True, text=True, cwd=home, env={**os.environ, "HOME": str(home)})
    finally:
        shutil.rmtree(home)
    if "plausible.cli" not in r.stderr and "Error" not in r.stderr:
        pytest.skip(f"the unprivileged user cannot run the package here: {r.stderr[-200:]}")
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr and str(target) in r.stderr and "Permission denied" in r.stderr


# -- item 4: no partial or misplaced output ------------------------------------------------

def test_fit_with_an_invalid_target_leaves_no_out_folder(tmp_path):
    out = tmp_path / "a" / "b"
    _refused(run("fit", "lambertian", "--target", tmp_path / "missing.csv", "--out", out), "missing.csv")
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("args", [("fit", "lambertian", "--target", "phong:n=10"), ("figures", "--only", "x")])
def test_out_dash_is_refused_where_the_command_writes_a_folder(args, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _refused(run(*args, "--out", "-"), "--out", "standard output")
    assert list(tmp_path.iterdir()) == []


# -- item 8: smaller ------------------------------------------------------------------------

def test_fit_time_limit_nan_is_refused_naming_the_option():
    _refused(run("fit", "lambertian", "--target", "phong:n=10", "--time-limit", "nan"), "--time-limit")


def test_a_negative_seed_is_refused_naming_the_option():
    _refused(run("fit", "lambertian", "--target", "phong:n=10", "--seed", "-1"), "--seed")


def test_a_parameter_given_twice_is_refused():
    _refused(run("eval", "ashikhmin-shirley:nu=1:nu=2", "--wi", "0,0", "--wo", "10,0"), "'nu'", "twice")
    _refused(run("eval", "lambertian", "-p", "rd=0.1", "-p", "rd=0.2", "--wi", "0,0", "--wo", "10,0"), "'rd'")
    with pytest.raises(ValueError, match="'nu' is given twice"):
        plausible.make("ashikhmin-shirley:nu=1:nu=2")


def test_minus_zero_prints_as_zero():
    m = plausible.make("ashikhmin-shirley:rd=-0:rs=-0,0,0.5")
    assert "rd=0)" in repr(m) and "-0" not in repr(m) and "-0" not in plausible.registry.spec_of(m)
    r = run("albedo", "ashikhmin-shirley", "-p", "rd=-0", "-n", "1")
    assert r.exit_code == 0 and "rd=0)" in r.output and "rd=-0" not in r.output


def test_an_empty_plot_path_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _refused(run("albedo", "lambertian", "-n", "2", "--plot", ""), "--plot", "empty")
    assert list(tmp_path.iterdir()) == []
