"""The ``plausible`` command line: a thin layer over the library."""

from __future__ import annotations

import errno
import math
import sys
import warnings

import click
import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from . import registry
from .analysis import albedo_curve, check as run_check, direction
from .progress import reporting, silent, within
from .text import fmt, write_atomic

console = Console()


def _fail(msg):
    raise click.UsageError(msg)


def _folder_out(ctx, param, value):
    """Callback of an ``--out`` that names a folder of files: ``-`` means standard output
    (the README's convention), which cannot hold them, so it is refused (not made a folder
    named ``-``)."""
    if value == "-":
        raise click.BadParameter("'-' means standard output, which cannot hold this command's files; "
                                 "give a folder", param=param)
    if value is not None and not value.strip():
        raise click.BadParameter("an empty path; give a folder", param=param)
    return value


class _FiniteRange(click.FloatRange):
    """:class:`click.FloatRange` that also refuses NaN (which every comparison lets through)."""

    def convert(self, value, param, ctx):
        v = super().convert(value, param, ctx)
        if v is not None and math.isnan(v):
            self.fail(f"{value!r} is not a number; give one in the range {self._describe_range()}", param, ctx)
        return v


def _model(name, assignments):
    try:
        return registry.make_from_spec(name, **registry.parse_assignments(assignments))
    except ValueError as e:
        _fail(str(e))


def _angles(text, what):
    try:
        t, p = (float(x) for x in text.split(","))
    except ValueError:
        _fail(f"{what} must be THETA_DEG,PHI_DEG (e.g. 30,0), got {text!r}")
    if not (0 <= t <= 90):
        below = " (below the horizon, where a BRDF is not defined)" if 90 < t <= 180 else ""
        _fail(f"{what}: theta must lie in [0, 90] degrees, got {t:g}{below}")
    if not math.isfinite(p):
        _fail(f"{what}: phi must be a finite angle in degrees, got {p}")
    return direction(math.radians(t), math.radians(p))


class _Bar:
    """The command line's progress display: a :mod:`plausible.progress` factory
    showing one Rich bar per announced total (removed when it completes) on a
    terminal, and nothing on a pipe.

    A context manager, and the ambient reporter inside it: the display starts at
    the first announced total and stops on leaving the ``with`` block, however
    it is left (done, time limit, error, Ctrl-C), so the bar never stays on
    screen and the cursor is always shown again.  ``main`` enters one for every
    command (``click``'s ``with_resource``).
    """

    def __init__(self, enabled=True):
        self.enabled = enabled and console.is_terminal
        self.prog = None
        self._ambient = None

    def __enter__(self):
        self._ambient = reporting(self)
        self._ambient.__enter__()
        return self

    def __exit__(self, *exc):
        try:
            if self.prog is not None:
                self.prog.stop()
                self.prog = None
        finally:
            self._ambient.__exit__(None, None, None)

    def __call__(self, total, label=""):
        if not self.enabled or total <= 0:
            return silent(total)
        if self.prog is None:
            self.prog = Progress(TextColumn("{task.description}"), BarColumn(),
                                 TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
                                 console=console, transient=True)
            self.prog.start()
        prog = self.prog
        task = prog.add_task(escape(label or "working"), total=total)
        done = [0]

        def tick(n=1):
            if done[0] < total:
                done[0] += n
                prog.advance(task, n)
                if done[0] >= total:      # a finished bar leaves the screen
                    prog.remove_task(task)

        return tick


def _bar():
    """The command's progress display (see :class:`_Bar`)."""
    return click.get_current_context().find_object(_Bar) or silent


PARAM_OPT = click.option("-p", "--param", "params", multiple=True, metavar="NAME=VALUE",
                         help="Model parameter (repeatable); colours as r,g,b.")


#: Console width on a pipe or file: wide enough that no table cell is cut or
#: folded (Rich's default there is 80 columns, which cut the material keys that
#: users copy); a terminal keeps its own width, and COLUMNS still sets one.
PIPE_WIDTH = 10_000


class _SystemRefused(click.ClickException):
    """A file or folder the command was given could not be read or written (a
    read-only or full disk, no permission): its path and the system's reason, status 2
    like any other bad input, no traceback."""

    exit_code = 2


def _os_error_text(e: OSError) -> str:
    """``"cannot use PATH: REASON"`` for an :class:`OSError` (both paths of a rename)."""
    paths = [str(p) for p in (e.filename, e.filename2) if p is not None]
    what = " -> ".join(paths) if paths else "the output"
    return f"cannot use {what}: {e.strerror or e}" + (
        " (the disk is full: free some space and run the command again)" if e.errno == errno.ENOSPC else "")


class _Group(click.Group):
    """The command group: Ctrl-C ends any command with status 130 (128 + SIGINT,
    the shell's convention; 1 means "a property fails"), after the progress
    display is cleared.  An :class:`OSError` that reaches it (a file given to the
    command that cannot be read, a folder on a read-only or full disk) ends it with
    status 2 and one line naming the path and the reason (:class:`_SystemRefused`):
    the one place that maps them, so no command shows a traceback for them.  A closed
    pipe (EPIPE) is left to Click."""

    def invoke(self, ctx):
        try:
            _check_environment()
            return super().invoke(ctx)
        except KeyboardInterrupt:
            click.echo("interrupted", err=True)
            ctx.exit(130)
        except OSError as e:
            if e.errno == errno.EPIPE:
                raise
            raise _SystemRefused(_os_error_text(e)) from None


def _check_environment():
    """``$PLAUSIBLE_BACKEND`` and ``$PLAUSIBLE_VARIANT``, checked before any command runs: a value that
    names nothing is a usage error naming the variable and its choices (status 2), not a traceback where a
    command first reads it nor a value a command ignores.  (A variant that is a name but does not render
    on this machine is refused where a command renders, as ``--variant``.)"""
    import os

    from .arrays import backend
    from .mitsuba.variant import ENV, is_name

    try:
        backend.requested()
    except ValueError as e:
        _fail(str(e))
    v = os.environ.get(ENV, "")
    if v.strip() and not is_name(v):
        _fail(f"environment variable {ENV} must be auto, cuda, llvm, scalar or a Mitsuba variant name "
              f"(llvm_ad_rgb, cuda_ad_rgb, ...); got {v!r}")


def _version(ctx, param, value):
    """``--version``: the version, then where this machine computes and renders (issue 42)."""
    if not value or ctx.resilient_parsing:
        return
    from importlib.metadata import PackageNotFoundError, version

    from .arrays import backend
    from .mitsuba import variant

    try:
        ver = version("plausible")
    except PackageNotFoundError:   # pragma: no cover - a source tree without metadata
        ver = "unknown"
    click.echo(f"plausible, version {ver}")
    click.echo("float64 backends: numpy" + "".join(f", {d} (Dr.Jit)" for d in backend.devices())
               + f"; 'drjit' and 'auto' use {backend.devices()[0] if backend.devices() else 'numpy'}")
    have = variant.available()
    try:
        pick = variant.preferred("rgb")
    except ValueError:
        pick = "none"
    click.echo(f"Mitsuba variants: {', '.join(have) or 'none (pip install plausible[render])'}; renders use {pick}")
    ctx.exit(0)


def _set_variant(ctx, param, value):
    """``--variant``: the Mitsuba device or RGB variant of every render of this command."""
    if value is None:
        return value
    from .mitsuba import variant

    try:
        variant.prefer(value)
    except ValueError as e:
        raise click.BadParameter(str(e), ctx=ctx, param=param)
    return value


def _set_backend(ctx, param, value):
    """``--backend``: the float64 backend (``$PLAUSIBLE_BACKEND``) of this command."""
    if value is None:
        return value
    import os

    from .arrays import backend

    os.environ[backend.ENV] = value
    try:
        if value in backend.DEVICES or value == "drjit":
            backend.device(value)
    except ValueError as e:
        raise click.BadParameter(str(e), ctx=ctx, param=param)
    return value


#: ``--variant``, on the group and on the commands that render.
VARIANT_OPT = click.option(
    "--variant", metavar="NAME", expose_value=False, is_eager=True, callback=_set_variant,
    help="Mitsuba device or variant for renders: auto (CUDA where a GPU is found, else LLVM), cuda, llvm, "
         "scalar, or an RGB variant such as cuda_ad_rgb ($PLAUSIBLE_VARIANT).")


@click.group(cls=_Group, context_settings=dict(help_option_names=["-h", "--help"]))
@click.option("--version", is_flag=True, expose_value=False, is_eager=True, callback=_version,
              help="Show the version, the float64 backends and the Mitsuba variants of this machine, and exit.")
@VARIANT_OPT
@click.option("--backend", type=click.Choice(["auto", "numpy", "drjit", "llvm", "cuda"]), expose_value=False,
              callback=_set_backend,
              help="Array backend of the float64 library and analysis ($PLAUSIBLE_BACKEND): drjit is CUDA "
                   "where a GPU is found, else LLVM.")
@click.pass_context
def main(ctx):
    """Physically plausible BRDFs: evaluate, sample, check, fit, export and render.

    The Phong family (Ashikhmin & Shirley, Modified Phong, reciprocal Phong and
    Blinn, albedo pumping-up), Lafortune, Schlick, Ward, Cook-Torrance, He-Torrance,
    Low and more; the published MERL fits (material:NAME@FIT); any Mitsuba BSDF or
    Python callable through the same checks.
    """
    import os

    if not console.is_terminal and not os.environ.get("COLUMNS"):
        console.width = PIPE_WIDTH
    ctx.obj = ctx.with_resource(_Bar())


def _echo_json(data):
    import json

    from .text import jsonable

    click.echo(json.dumps(jsonable(data), indent=1, allow_nan=False))


def _model_entry(name) -> dict:
    inf = registry.info(name)
    return dict(name=inf.name, description=inf.description, reciprocal=inf.reciprocal,
                energy_conserving=inf.energy_conserving, references=list(inf.references),
                params=[dict(name=p.name, default=p.default, lo=p.lo if math.isfinite(p.lo) else None,
                             hi=p.hi if math.isfinite(p.hi) else None, kind=p.kind, doc=p.doc,
                             **({"choices": list(p.choices)} if p.choices else {}),
                             **({"integer": True} if p.integer else {})) for p in inf.params])


@main.command()
@click.argument("name", required=False)
@click.option("--json", "as_json", is_flag=True, help="Print the models as JSON.")
def models(name, as_json):
    """List every registered model with its parameters, defaults and ranges;
    with NAME, that model alone (its parameters, claims and references)."""
    if name is not None:
        try:
            entry = _model_entry(name)
        except ValueError as e:
            _fail(str(e))
        if as_json:
            return _echo_json(entry)
        inf = registry.info(name)
        console.print(f"[bold]{escape(name)}[/bold]: {escape(inf.description)}", soft_wrap=True)
        claims = ["reciprocal" if inf.reciprocal else "not reciprocal",
                  "energy conserving" if inf.energy_conserving else "not energy conserving"]
        console.print(f"claims: {', '.join(claims)}", soft_wrap=True)
        t = Table(title="parameters")
        for col in ("name", "default", "range", "kind", "meaning"):
            t.add_column(col)
        for p in inf.params:
            t.add_row(escape(p.name), escape(_fmt(p.default)), escape(p.range_text()), p.kind, escape(p.doc))
        console.print(t)
        for ref in inf.references:
            console.print(f"reference: {escape(ref)}", soft_wrap=True)
        return
    if as_json:
        return _echo_json([_model_entry(n) for n in registry.names()])
    t = Table(title="registered models", show_lines=True)
    t.add_column("model", style="bold", no_wrap=True, min_width=max(map(len, registry.names())))
    t.add_column("parameters (default, range)")
    t.add_column("description")
    for name in registry.names():
        inf = registry.info(name)
        ps = "\n".join(f"{p.name} = {_fmt(p.default)}  {p.range_text()}  ({p.kind})" for p in inf.params)
        flags = [] if inf.reciprocal else ["not reciprocal"]
        if not inf.energy_conserving:
            flags.append("not energy conserving")
        desc = inf.description + (f" [{'; '.join(flags)}]" if flags else "")
        t.add_row(escape(name), escape(ps), escape(desc))   # text, not Rich markup: "[max]" stays
    console.print(t)


def _fmt(v):   # the syntax of -p: colours as r,g,b
    return fmt(v, sep=",", brackets=False, sequences=(np.ndarray, list, tuple))


@main.command("eval")
@click.argument("model")
@PARAM_OPT
@click.option("--wi", required=True, multiple=True, metavar="THETA_DEG,PHI_DEG",
              help="Direction wi (to the light); repeatable.")
@click.option("--wo", required=True, multiple=True, metavar="THETA_DEG,PHI_DEG",
              help="Direction wo (to the viewer); repeatable.")
@click.option("--json", "as_json", is_flag=True, help="Print the pairs and values as JSON.")
def eval_cmd(model, params, wi, wo, as_json):
    """Print the BRDF value f(wi, wo) (no cosine factor), one line per pair.

    Several pairs: repeat --wi and --wo (the k-th --wi with the k-th --wo), or
    give one --wi and several --wo (or the reverse).
    """
    m = _model(model, params)
    if len(wi) != len(wo) and 1 not in (len(wi), len(wo)):
        _fail(f"give as many --wi as --wo (paired in order), or one of either; got {len(wi)} --wi "
              f"and {len(wo)} --wo")
    n = max(len(wi), len(wo))
    wis, wos = (list(x) * n if len(x) == 1 else list(x) for x in (wi, wo))
    a = np.array([_angles(t, "--wi") for t in wis])
    b = np.array([_angles(t, "--wo") for t in wos])
    f = m.eval(a, b)
    if as_json:
        return _echo_json([dict(wi=[float(x) for x in s.split(",")], wo=[float(x) for x in t.split(",")],
                                f=np.atleast_1d(v)) for s, t, v in zip(wis, wos, f)])
    for v in f:
        click.echo(" ".join(f"{x:.10g}" for x in np.atleast_1d(v)))


@main.command()
@click.argument("model", required=False)
@PARAM_OPT
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@click.option("--all", "all_models", is_flag=True,
              help="Check every registered model on its defaults and extreme parameters.")
@click.option("--quick", is_flag=True, help="Fewer directions and samples.")
@click.option("--verbose", is_flag=True, help="With --all: every parameter set's full report too.")
@click.option("--mitsuba", "mitsuba_dict", metavar="JSON",
              help='A Mitsuba 3 BSDF as mi.load_dict takes it, e.g. \'{"type": "roughconductor", "alpha": 0.2}\'.')
@click.option("--mitsuba-xml", type=click.Path(exists=True, dir_okay=False), metavar="FILE",
              help="A Mitsuba 3 XML file (a <bsdf> or a scene); --id names the BSDF.")
@click.option("--id", "bsdf_id", metavar="NAME", help="The id of the BSDF in --mitsuba-xml.")
@click.option("--python", "python_obj", metavar="MODULE:NAME",
              help="A callable f(wi, wo) (optional .pdf and .sample), an object with eval/pdf/sample, "
                   "or a mitsuba.BSDF, importable as package.module:name.")
@click.option("--materials", "all_materials", is_flag=True,
              help="Check every published MERL fit (reciprocity, largest albedo); see docs/materials.md.")
@click.option("--fit", "fit_keys", multiple=True, metavar="FIT",
              help="With --materials: only this fit set, e.g. ngan2005/ward (repeatable).")
@click.option("--material", "material_names", multiple=True, metavar="NAME",
              help="With --materials: only this material, e.g. alum-bronze (repeatable).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), metavar="DIR",
              help="With --materials: write materials-table.md/.csv (and materials.md's summary) here.")
@click.option("--blender", "blend_file", type=click.Path(dir_okay=False), metavar="FILE.blend",
              help="Acquire a material of a Blender file in Cycles (--material NAME) and check it "
                   "(docs/blender.md).")
@click.option("--tangent", is_flag=True,
              help="With --blender: the tangent-resolved acquisition, for an anisotropic material (reciprocity "
                   "at the same tangent frame, the albedo over theta and phi; 97 renders; docs/blender.md).")
@click.option("--jobs", type=click.IntRange(1, 64), metavar="N",
              help="With --materials or --all: worker processes (default: the usable cores, at most 2).")
@click.option("--scheduler", metavar="ADDRESS",
              help="With --materials: a running Dask scheduler (tcp://host:8786) instead of --jobs.")
def check(model, params, as_json, all_models, quick, verbose, mitsuba_dict, mitsuba_xml, bsdf_id,
          python_obj, all_materials, fit_keys, material_names, out_dir, blend_file, tangent, jobs, scheduler):
    """Verify reciprocity, energy conservation, sampling consistency and chi-square.

    MODEL is a registered model; or check any BSDF with --mitsuba, --mitsuba-xml or
    --python (see docs/analysis.md); or a Cycles material of a .blend file, acquired in
    Blender, with --blender FILE --material NAME (docs/blender.md).  Exits with status 1 when a property fails.
    A registered model's report ends with whether it holds what the model
    claims ("as claimed").  With --all: every registered model on its defaults
    and extremes, one row each in a compact table (--verbose: every full report
    too); a model whose check raises is reported and the others still run, a
    summary line ends the output, and the status is 1 when a model fails a
    property it claims.  --json: non-applicable checks have "passed" and
    "figure" null, and "counts" tallies passed, failed and not applicable.
    With --materials: every published fit (or those of --fit, --material) as
    one table, or a JSON list of reports; the status is 1 when a fit gains
    energy or is not reciprocal.
    """
    import json

    from .analysis.report import CheckReport
    from .analysis.suite import model_variants

    if blend_file is not None:
        return _check_blender(blend_file, material_names, quick, as_json,
                              model or all_models or params or mitsuba_dict or mitsuba_xml or python_obj
                              or all_materials or fit_keys or out_dir, tangent)
    if tangent:
        _fail("--tangent chooses the acquisition of --blender FILE --material NAME; give --blender")
    if all_materials or fit_keys or material_names or out_dir or scheduler or (jobs and not all_models):
        return _check_materials(all_materials, fit_keys, material_names, out_dir, (jobs, scheduler), quick, as_json,
                                model or all_models or params or mitsuba_dict or mitsuba_xml or python_obj)
    foreign = _foreign_bsdf(mitsuba_dict, mitsuba_xml, bsdf_id, python_obj, model or all_models)
    if foreign is not None and params:      # was ignored: the report showed the BSDF's own parameters
        _fail("-p sets the parameters of a registered MODEL; a --mitsuba dict, --mitsuba-xml file or --python "
              "object carries its own (put them in the dict or the XML)")
    if not model and not all_models and foreign is None:
        _fail("give a MODEL, --all, --mitsuba, --mitsuba-xml or --python")
    if all_models and (model or params):
        _fail(f"--all checks every registered model on its own parameter sets; it takes no MODEL or -p "
              f"(got {' '.join([model or ''] + ['-p ' + p for p in params]).strip()!r})")
    if all_models:
        targets = [m for name in registry.names() for m in model_variants(name)]
    elif foreign is not None:
        targets = [foreign]
    else:
        targets = [_model(model, params)]
    reports, verdicts, rows = [], [], []
    for m, rep in zip(targets, _each_report(targets, all_models, quick, jobs, as_json)):
        if isinstance(rep, Exception):   # --all: one model's failure is reported, the others still run
            reports.append(dict(CheckReport(m.name, m.params).to_dict(), passed=False,
                                error=f"{type(rep).__name__}: {rep}"))
            verdicts.append(False)
            rows.append((m, None, False))
            if not as_json:
                console.print(f"[red]check {escape(repr(m))} failed with an error:[/red] "
                              f"{escape(reports[-1]['error'])}")
            continue
        reports.append(rep.to_dict())
        info = getattr(m, "info", None)
        claimed = rep.as_claimed(info) if info is not None else None
        verdicts.append(claimed if all_models else rep.passed)
        rows.append((m, rep, claimed))
        if not as_json and (not all_models or verbose):
            _print_report(rep)
            if not all_models and claimed is not None:
                console.print(_claim_line(rep, info), soft_wrap=True)
    if as_json:
        click.echo(json.dumps(reports if all_models else reports[0], indent=1))
    if all_models and not as_json:   # the implausible baselines may fail what they do not claim
        _print_compact(rows)
        _print_summary(reports, verdicts)
    sys.exit(0 if all(verdicts) else 1)


def _check_blender(blend_file, names, quick, as_json, other, tangent=False):
    """check --blender FILE --material NAME [--tangent]: the material acquired in Cycles and checked."""
    import json

    from .blender import BlenderUnavailable, check_material

    if other:
        _fail("--blender checks one material of a .blend file; it takes only --material, --tangent, --quick and "
              "--json")
    if len(names) != 1:
        _fail(f"--blender needs exactly one --material NAME (the material in {blend_file}), got {len(names)}")
    try:
        rep, _ = check_material(blend_file, names[0], quick=quick, tangent=tangent,
                                progress=silent if as_json else _bar())
    except ValueError as e:
        _fail(str(e).replace("blend: ", "--blender: ").replace("material: ", "--material: "))
    except BlenderUnavailable as e:
        _fail(str(e))
    if as_json:
        click.echo(json.dumps(rep.to_dict(), indent=1))
    else:
        _print_report(rep)
    sys.exit(0 if rep.passed else 1)


def _each_report(targets, all_models, quick, jobs, as_json):
    """Each target's :class:`CheckReport` in order, or (with --all) the exception its
    check raised; --all with more than one job checks whole models in worker processes."""
    if all_models and (jobs or _default_jobs()) > 1:
        from .analysis.suite import check_many, exit_text

        def died(m, code, retried):     # on stderr: --json keeps stdout the reports
            click.echo(f"check {m!r}: its worker process died ({exit_text(code)}); "
                       + ("checking it again in a fresh worker" if retried else "not tried again"), err=True)

        yield from check_many(targets, quick=quick, jobs=jobs or _default_jobs(),
                              progress=silent if as_json else _bar(), on_worker_death=died)
        return
    for m in targets:
        try:
            yield run_check(m, quick=quick, progress=silent if as_json else _bar())
        except Exception as e:   # noqa: BLE001  one model's failure is reported, the others still run
            if not all_models:
                raise
            yield e


def _print_summary(reports, verdicts):
    """check --all's last line: how many sets hold what they claim, and which do not."""
    errors = sum("error" in r for r in reports)
    bad = [f"{r['model']} {_fmt_params(r['params'])}" for r, v in zip(reports, verdicts) if not v]
    click.echo(f"{len(reports)} parameter sets of {len(registry.names())} models checked: "
               f"{verdicts.count(True)} as claimed, {len(bad) - errors} not as claimed, "
               f"{errors} failed with an error" + (f" ({'; '.join(bad)})" if bad else ""))


def _materials_rows(M, keys, names, quick, jobs, scheduler, out_dir, tick, n):
    """The rows of ``check --materials`` (with ``--out``: journaled in ``DIR/.materials-rows.jsonl``,
    claimed, resumed; the tables written and the journal removed once every row is there)."""
    from pathlib import Path

    journal = Path(out_dir) / ".materials-rows.jsonl" if out_dir else None
    runs = []
    try:
        if journal is not None:
            journal.parent.mkdir(parents=True, exist_ok=True)
        rows = M.check_fits(keys, names, quick=quick, jobs=jobs or _default_jobs(), progress=tick,
                            scheduler=scheduler, journal=journal, summary=runs)
    except KeyboardInterrupt:
        console.print(f"[yellow]interrupted[/yellow]: the rows checked so far are in {escape(str(journal))}; "
                      "run the same command again to resume" if journal else "[yellow]interrupted[/yellow]",
                      soft_wrap=True)
        sys.exit(130)
    except OSError as e:
        _fail(f"--out {out_dir}: cannot write there ({e.strerror or e})")
    except ValueError as e:
        _fail(_scheduler_flag(e))
    for s in runs:
        _shared_note(s, "fits", out_dir)
    if journal is None or len(rows) < n:
        return rows, None
    try:
        written = M.write_tables(rows, out_dir)
    except OSError as e:
        _fail(f"--out {out_dir}: cannot write the tables ({e.strerror or e}); the rows are kept in {journal}: "
              "run the same command again once there is room")
    journal.unlink(missing_ok=True)
    return rows, written


def _default_jobs() -> int:
    from .analysis.suite import default_jobs

    return default_jobs()


def _check_materials(all_materials, fit_keys, names, out_dir, where, quick, as_json, other):
    """``check --materials``: :func:`plausible.analysis.materials.check_fits` as a table or JSON."""
    import json

    from .analysis import materials as M
    from .catalogue import fit_set, materials, suggest

    jobs, scheduler = where
    if not all_materials:
        _fail("--fit, --material, --out, --jobs and --scheduler go with --materials")
    if out_dir is not None:
        _no_stdout(out_dir, "check --materials --out writes materials-table.md/.csv into a folder")
        if fit_keys or names:
            _fail("--out writes the table of every published fit (materials-table.md/.csv and the summary in "
                  "materials.md); a run filtered by --fit/--material would replace it with a part: leave out "
                  "--out to print the filtered table (or --json), or --fit/--material to write the whole one")
    if other:
        _fail("--materials checks the published fits; it takes no MODEL, -p, --all, --mitsuba, "
              "--mitsuba-xml or --python")
    try:
        sets = [fit_set(k) for k in fit_keys]
    except ValueError as e:
        _fail(str(e))
    for fs in sets:
        if not fs.built:
            _fail(f"--fit {fs.key} cannot be loaded: {fs.reason}")
    keys = [fs.key for fs in sets] or None
    names = list(names) or None
    known = materials()
    for n in names or ():
        if n not in known:
            _fail(f"--material: unknown material {n!r}{suggest(n, list(known))}")
    work = M.work_list(keys, names)
    if not work:
        _fail(f"no fit set {'of ' + ', '.join(keys) + ' ' if keys else ''}has the material(s) {', '.join(names)}")
    if out_dir:     # before the work: a folder that cannot be made or written fails now
        from .plotting import check_new_dir

        try:
            check_new_dir(out_dir, "--out")
        except ValueError as e:
            _fail(str(e))
    tick = silent if as_json else _bar()
    t = tick(len(work), "checking published fits")
    rows, written = _materials_rows(M, keys, names, quick, jobs, scheduler, out_dir, t, len(work))
    bad = [r for r in rows if r.gains_energy or not r.reciprocal]
    if as_json:
        click.echo(json.dumps([r.to_dict() for r in rows], indent=1))
    else:
        tab = Table(title="published fits", title_justify="left")
        for c in ("fit", "fits", "gain energy", "largest albedo (material, angle)", "median largest albedo",
                  "largest asymmetry"):
            tab.add_column(c, overflow="fold")
        for x in M.summary(rows):
            style = "red" if x["gain"] else "green"
            tab.add_row(escape(x["fit"]), str(x["n"]), f"[{style}]{x['gain']}[/{style}]",
                        escape(f"{x['worst_albedo']:.4f} ({x['worst']}, {x['worst_theta']:g}°)"),
                        f"{x['median']:.4f}", f"{x['asymmetry']:.1e}")
        console.print(tab)
        for r in bad:
            what = f"gains energy: largest albedo {r.max_albedo:.4f} at {r.theta_deg:g}° ({r.channel})" \
                if r.gains_energy else f"not reciprocal: asymmetry {r.asymmetry:.1e}"
            console.print(f"[red]{escape(r.material)}@{escape(r.fit)}[/red] {escape(what)}")
        click.echo(f"{len(rows)} fits of {len({r.fit for r in rows})} fit sets checked"
                   f"{' (quick)' if quick else ''}: {len(rows) - len(bad)} plausible, {len(bad)} not")
        if written:
            click.echo("wrote " + ", ".join(str(p) for p in written))
        elif out_dir:
            click.echo(f"{len(work) - len(rows)} fits are another run's: the run that checks the last one writes "
                       f"the tables into {out_dir}")
    sys.exit(1 if bad else 0)


def _claim_line(rep, info) -> str:
    """Does the report agree with what the model claims?  (The explorer's verdict line.)"""
    claims = ("reciprocal" if info.reciprocal else "not reciprocal") + ", " + \
        ("energy conserving" if info.energy_conserving else "not energy conserving")
    if rep.as_claimed(info):
        return f"[green]as claimed[/green] ({escape(info.name)} claims: {claims})"
    return f"[red]not as claimed[/red] ({escape(info.name)} claims: {claims})"


#: The columns of the compact ``check --all`` table: the four properties.
_PROPERTIES = ("reciprocity", "energy", "sampling", "chi2")


def _print_compact(rows):
    """``check --all``: one row per parameter set (verdict of each property, the claim)."""
    t = Table(title="check --all", title_justify="left")
    t.add_column("model", no_wrap=True)
    t.add_column("parameters")
    for c in _PROPERTIES + ("as claimed",):
        t.add_column(c, no_wrap=True)
    colour = {"PASS": "green", "FAIL": "red", "N/A": "yellow", "error": "red"}
    for m, rep, claimed in rows:
        if rep is None:
            cells = ["error"] * len(_PROPERTIES)
        else:
            verdict = {r[0]: r[3] for r in rep.rows()}
            cells = [verdict.get(p, "-") for p in _PROPERTIES]
        cells = [f"[{colour.get(c, 'white')}]{c}[/]" for c in cells]
        yes = "-" if claimed is None else "[green]yes[/]" if claimed else "[red]no[/]"
        t.add_row(escape(m.name), escape(_fmt_params(m.params)), *cells, yes)
    console.print(t)


def _fmt_params(ps):
    return "{" + ", ".join(f"{k}={_fmt(v)}" for k, v in ps.items()) + "}"


def _foreign_bsdf(mitsuba_dict, mitsuba_xml, bsdf_id, python_obj, other):
    """The object of --mitsuba / --mitsuba-xml / --python as a contract (None if none given)."""
    import json

    from .analysis.adapters import as_bxdf, load_python

    given = [o for o, v in (("--mitsuba", mitsuba_dict), ("--mitsuba-xml", mitsuba_xml),
                            ("--python", python_obj)) if v]
    if bsdf_id and not mitsuba_xml:
        _fail("--id names a BSDF in --mitsuba-xml; give --mitsuba-xml FILE")
    if not given:
        return None
    if len(given) > 1 or other:
        _fail(f"give one of MODEL, --all, --mitsuba, --mitsuba-xml, --python (got {', '.join(given)}"
              f"{' and a MODEL or --all' if other else ''})")
    # the library's errors name its arguments (target, d, path, id); the flags are ours
    flag = given[0]
    try:
        if mitsuba_dict:
            from .analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

            try:
                d = json.loads(mitsuba_dict)
            except json.JSONDecodeError as e:
                _fail(f"--mitsuba must be a JSON object, e.g. '{{\"type\": \"diffuse\"}}': {e}")
            if not isinstance(d, dict) or "type" not in d:
                _fail(f"--mitsuba must be a JSON object with a 'type', as mi.load_dict takes it; got {d!r}")
            return MitsubaBSDF(load_bsdf_dict(d), params={k: v for k, v in d.items() if k != "type"},
                               name=d["type"])
        if mitsuba_xml:
            from .analysis.mitsuba_bsdf import load_bsdf_xml

            return as_bxdf(load_bsdf_xml(mitsuba_xml, bsdf_id))
        return as_bxdf(load_python(python_obj))
    except (ValueError, TypeError, RuntimeError) as e:
        hint = " (--id NAME chooses one)" if mitsuba_xml and not bsdf_id and "no id was given" in str(e) else ""
        _fail(f"{flag}: {e}{hint}")


def _print_report(rep):
    t = Table(title=escape(f"{rep.model} {rep.params}"), title_justify="left")
    for c in ("property", "figure", "bound", "verdict", "worst case"):
        t.add_column(c, overflow="fold")
    for row in rep.rows():
        style = {"PASS": "green", "UNRESOLVED": "yellow"}.get(row[3], "red")
        style = "yellow" if row[3] == "N/A" else style
        t.add_row(*map(escape, row[:3]), f"[{style}]{row[3]}[/{style}]", escape(row[4]))
    console.print(t)
    for n in rep.notes:
        console.print(f"note: {escape(n)}")
    if rep.reach:
        console.print(f"reach: {escape(rep.reach['text'])}", soft_wrap=True)


@main.command()
@click.argument("models", nargs=-1, required=True)
@PARAM_OPT
@click.option("--plot", type=click.Path(dir_okay=False), help="Write the curves to this image file.")
@click.option("--phi", default=0.0, show_default=True, callback=lambda c, p, v: _finite(p, v),
              help="Azimuth of incidence (degrees).")
@click.option("-n", "--points", default=46, show_default=True, type=click.IntRange(1, 100_000),
              help="Number of incidence angles.")
@click.option("--log", "log_axis", is_flag=True,
              help="With --plot: a logarithmic albedo axis (else a curve far above the others is clipped, "
                   "with a note).")
@click.option("--json", "as_json", is_flag=True, help="Print the curves as JSON.")
def albedo(models, params, plot, phi, points, as_json, log_axis):
    """Directional albedo against incidence angle, for one or more models.

    MODELS are names with optional parameters, e.g. reciprocal-phong:n=150
    ashikhmin-shirley:nu=10:nv=10:rs=1:rd=0 (-p applies to every model).
    """
    from .plotting import check_image_path, default_thetas, plot_albedo_curves

    if log_axis and plot is None:   # was ignored: the table has no axis
        _fail("--log sets the albedo axis of --plot FILE; give --plot (the printed table has no axis)")
    if plot is not None:    # before the work: a path that cannot be written ('' included) fails now
        try:
            check_image_path(plot, "--plot")
        except ValueError as e:
            _fail(str(e))
    th = default_thetas(points)
    targets = [_model(spec, params) for spec in models]
    tick = (silent if as_json else _bar())(len(targets) * len(th), "albedo")
    curves = [(repr(m), th, albedo_curve(m, th, math.radians(phi), progress=within(tick))) for m in targets]
    if as_json:
        _echo_json([dict(model=registry.spec_of(m), phi_deg=phi, theta_deg=np.degrees(th), value=r.value,
                         error=r.error) for m, (_, _, r) in zip(targets, curves)])
        if plot is not None:
            plot_albedo_curves(curves, plot, yscale="log" if log_axis else "linear")
        return
    t = Table(title="directional albedo")
    t.add_column("theta (deg)")
    for label, _, _ in curves:
        t.add_column(escape(label), overflow="fold")
    for i, x in enumerate(th):
        t.add_row(f"{math.degrees(x):.2f}", *[_fmt_alb(r.value[i], r.error[i]) for _, _, r in curves])
    console.print(t)
    if plot is not None:
        plot_albedo_curves(curves, plot, yscale="log" if log_axis else "linear")
        console.print(f"wrote {escape(str(plot))}")


def _finite(param, v):
    if not math.isfinite(v):
        raise click.BadParameter(f"must be a finite number, got {v}", param=param)
    return v


def _fmt_alb(v, e):
    v = np.atleast_1d(v)
    e = np.atleast_1d(e)
    return " ".join(f"{a:.6f}" for a in v) + f" (+-{float(np.max(e)):.1e})"


# -- fit (plausible.fitting) ------------------------------------------------------------
@main.command("fit")
@click.argument("model")
@click.option("--target", required=True, metavar="FILE_OR_MODEL",
              help="A model spec (name:k=v), a published fit (material:NAME@FIT), a MERL .binary file or a CSV "
                   "table (wi xyz, wo xyz, f).")
@PARAM_OPT
@click.option("--metric", type=click.Choice(["perceptual", "l2-cos", "log"]), default="perceptual",
              show_default=True, help="Error metric minimised (see docs/fitting.md).")
@click.option("--out", type=click.Path(file_okay=False), callback=_folder_out,
              help="Write plane.png, albedo.png, fit.json here (made after the fit).")
@click.option("--starts", type=click.IntRange(1), default=4, show_default=True, help="Optimiser starts.")
@click.option("--time-limit", type=_FiniteRange(0), help="Stop after this many seconds (best so far).")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(0), help="Seed of the random starts.")
def fit_cmd(model, target, params, metric, out, starts, time_limit, seed):
    """Fit MODEL's parameters to a target; -p fixes parameters of MODEL."""
    from .fitting import BoundWarning, UnconstrainedWarning, fit as run_fit
    from .fitting.plots import write_plots
    from .plotting import check_new_dir

    try:
        if out is not None:     # before the fit: a folder that cannot be made fails now (made after it)
            check_new_dir(out, "--out")
        with warnings.catch_warnings(record=True) as caught:     # printed below, as the command's own line
            warnings.simplefilter("always", UnconstrainedWarning)
            warnings.simplefilter("always", BoundWarning)
            res = run_fit(model, target, metric, fixed=registry.parse_assignments(params), starts=starts,
                          seed=seed, time_limit=time_limit, progress=_bar())
    except ValueError as e:
        _fail(str(e))
    console.print(f"[bold]{escape(res.model.name)}[/bold] fitted to {escape(res.target.label)} ({metric}, "
                  f"{res.evaluations} evaluations, {res.seconds:.1f} s)", soft_wrap=True)
    t = Table()
    t.add_column("parameter"); t.add_column("value")
    for k, v in res.params.items():
        t.add_row(escape(k), escape(_fmt(v)))
    console.print(t)
    e = Table()
    e.add_column("error (every metric)"); e.add_column("value")
    for k, v in res.errors.items():
        e.add_row(k, "n/a (no target albedo)" if v is None else f"{v:.6g}")
    console.print(e)
    for note in res.notes:
        console.print(escape(note), soft_wrap=True)
    _print_looks(res.target.model, res.model, "target")
    if res.timed_out:
        console.print("[yellow]time limit reached: best point found so far[/yellow]")
    for w in caught:
        if issubclass(w.category, UnconstrainedWarning):
            console.print(f"[yellow]warning:[/yellow] {escape(str(w.message))}", soft_wrap=True)
        elif issubclass(w.category, BoundWarning):
            click.echo(f"warning: {w.message}", err=True)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if out is not None:
        for p in write_plots(res, out):
            console.print(f"wrote {escape(str(p))}")


@main.command("convert")
@click.argument("source")
@click.option("--to", "to", required=True, metavar="TARGET",
              help="mitsuba (the family chosen per material), mitsuba:TYPE (diffuse, roughconductor, roughplastic, blendbsdf, "
                   "blendbsdf-tir, principled), gltf, materialx, usd (the glTF fit as OpenPBR/UsdPreviewSurface), "
                   "blender (Principled BSDFs in a .blend or .py, verified in Cycles), or a registered model.")
@click.option("--out", required=True, type=click.Path(dir_okay=False), metavar="FILE",
              help="Output: .json (a dict of Mitsuba dicts by material name), .xml (<bsdf id=...> elements) "
                   "or .gltf (with --to gltf), .mtlx (--to materialx), .usda (--to usd), .blend or .py (--to blender); "
                   "- for standard output (that file's text with the text targets, else the .json's).")
@click.option("--metric", type=click.Choice(["perceptual", "l2-cos", "log"]), default="perceptual",
              show_default=True, help="Error metric minimised (see docs/fitting.md).")
@click.option("--nodes", type=click.Choice(["source", "gltf", "principled"]), default=None, metavar="TREE",
              help="With --to blender: the node tree written: source (default: a Lambertian plus Cook-Torrance "
                   "source as its own lobes, any other as gltf), gltf (the glTF fit; a dielectric part as glTF's "
                   "formula in nodes), principled (the glTF fit as one Principled BSDF). See docs/blender.md.")
@click.option("--json", "as_json", is_flag=True, help="Print the report of every material as JSON.")
def convert_cmd(source, to, out, metric, nodes, as_json):
    """Convert SOURCE's materials to TARGET, with the error measured (docs/convert.md).

    SOURCE: a model spec, material:NAME@FIT, a Mitsuba BSDF (.xml, or .json of dicts by name),
    or a Wavefront .mtl file.
    """
    from pathlib import Path

    from .conversion import GLTF_SHAPED, check_output, convert

    if out == "-" and as_json:
        _fail("--out - and --json both write to standard output: give --out a file")
    if str(to).strip() == "blender":
        return _convert_blender(source, out, metric, as_json, nodes or "source")
    if nodes is not None:
        _fail(f"--nodes chooses the node tree of --to blender; --to {to} writes no node tree: leave --nodes out")
    try:
        if out != "-":
            check_output(out, to, source)  # a bad --out is refused before minutes of fitting
        res = convert(source, to=to, metric=metric)
        if out == "-" and res.items:       # the file's text alone on stdout: .gltf for glTF, else .json
            click.echo(res.text(GLTF_SHAPED.get(res.to, ".json"), Path.cwd()), nl=False)
        path = res.write(out) if out != "-" and res.items else None
    except ValueError as e:
        _fail(str(e).replace("to: ", "--to: ").replace("out: ", "--out: "))
    if as_json:
        _echo_json(res.to_json())
    elif out != "-":
        _convert_table(res, path)
    for s in res.skipped:
        click.echo(f"warning: {s['skipped']}", err=True)
    if res.skipped:
        raise SystemExit(1)                # some materials skipped: the rest converted and written


def _convert_blender(source, out, metric, as_json, nodes="source"):
    """convert --to blender: Principled BSDFs (or node trees, ``--nodes``) in a .blend or .py, each
    verified in Cycles."""
    from .blender import BlenderUnavailable
    from .blender.convert import convert_to_blender

    try:
        res = convert_to_blender(source, out, metric, nodes=nodes, progress=silent if as_json else _bar())
    except ValueError as e:
        _fail(str(e).replace("to: ", "--to: ").replace("out: ", "--out: ").replace("nodes: ", "--nodes: "))
    except BlenderUnavailable as e:
        _fail(str(e))
    if as_json:
        _echo_json(res.to_json())
    else:
        t = Table()
        for col in ("material", "Blender material", "albedo diff. (source / fit)", "stderr", "FLIP", "highlight"):
            t.add_column(col)
        for v in res.verified:
            inp = v.description()
            fit = "-" if v.fit_albedo_difference is None else f"{v.fit_albedo_difference:.3f}"
            t.add_row(escape(v.name), escape(inp), f"{v.albedo_difference:.3f} / {fit}",
                      f"{v.albedo_stderr:.2g}", "-" if v.flip is None else f"{v.flip:.3f}",
                      "-" if v.highlight_ratio is None else f"x{v.highlight_ratio:.3g}")
        console.print(t)
        console.print(f"wrote {escape(str(res.path))} (each material read back from it, acquired in Cycles and "
                      "rendered in Cycles beside its source in Mitsuba)")
    for v in res.verified:
        for w in v.notes:
            click.echo(f"warning: {v.name}: {w}", err=True)
    for s in res.conversion.skipped:
        click.echo(f"warning: {s['skipped']}", err=True)
    if res.conversion.skipped:
        raise SystemExit(1)



def _convert_table(res, path):
    if not res.items:
        console.print(f"no material converted ({len(res.skipped)} skipped): nothing written")
        return
    t = Table()
    for col in ("material", "target", "perceptual", "albedo diff. 0 / 45 / 75 deg", "FLIP", "highlight", "warnings"):
        t.add_column(col)
    for c in res.items:
        diffs = " / ".join(f"{c.albedo[k]['max_abs_difference']:.3f}" for k in c.albedo) or "- (not fitted)"
        perceptual = c.errors.get("perceptual")
        flip, ratio = _looks_cells(c.looks)
        t.add_row(escape(c.name), escape(c.label), "-" if perceptual is None else f"{perceptual:.3g}", diffs,
                  flip, ratio, escape("; ".join(c.warnings)) or "-")
    console.print(t)
    for c in res.items:     # the image's verdict on stderr too: a warning, not a cell to find
        for w in (c.looks.warnings if c.looks is not None else ()):
            click.echo(f"warning: {c.name}: {w}", err=True)
    if path is not None:
        console.print(f"wrote {escape(str(path))}")


def _print_looks(source, result, what):
    """The fit or conversion beside its ``what`` (:func:`plausible.compare_looks`): FLIP and
    highlight ratios on stdout, a lost or invented highlight as a warning on stderr; a line
    saying why where there is nothing to render (a table target, no Mitsuba)."""
    from .mitsuba.looks import compare_looks

    if source is None:
        console.print(f"looks: not rendered (the {what} is a table, not a BSDF)")
        return
    try:
        looks = compare_looks(source, result)
    except (ValueError, ImportError) as err:
        console.print(f"looks: not rendered ({escape(str(err))})", soft_wrap=True)
        return
    console.print(f"looks, rendered beside the {what} (plausible.compare_looks): {looks.summary()}", soft_wrap=True)
    for w in looks.warnings:
        click.echo(f"warning: {w}", err=True)


def _looks_cells(looks):
    """The FLIP and highlight-ratio cells of a :class:`plausible.mitsuba.looks.Looks` (``-`` for None)."""
    if looks is None:
        return "-", "-"
    return f"{looks.flip:.3f}", f"x{looks.highlight_ratio:.3g}"


@main.command("convert-table")
@click.option("--out", required=True, type=click.Path(dir_okay=False), metavar="FILE.jsonl",
              help="Rows, one JSON line per conversion, appended as each finishes; rows already there are skipped.")
@click.option("--to", "to", default="mitsuba,gltf", show_default=True, metavar="A,B",
              help="Targets (comma-separated: mitsuba, gltf).")
@click.option("--fits", metavar="A,B,...", help="Fit sets (default: every loadable one).")
@click.option("--per-set", type=click.IntRange(1), help="Materials per fit set (alphabetical; default: all).")
@click.option("--limit", type=click.IntRange(0), help="At most this many conversions this run (0: only --markdown).")
@click.option("--workers", type=click.IntRange(0), default=0, show_default=True,
              help="Worker processes (0: one conversion after another in this process).")
@click.option("--markdown", "md", type=click.Path(dir_okay=False), metavar="FILE.md",
              help="Write the table (summary per fit set, every row) from every row of --out.")
@click.option("--redo", "--redo-target", "redo", metavar="A,B",
              help="Convert again first the rows of these targets (mitsuba:diffuse, ...), fit sets (ngan2005/ward) "
                   "or materials (material:NAME@FIT) made by other code.")
@click.option("--scheduler", metavar="ADDRESS", help="A running Dask scheduler (tcp://host:8786) instead of "
              "--workers.")
def convert_table_cmd(out, to, fits, per_set, limit, workers, md, redo, scheduler):
    """Convert every published fit (material:NAME@FIT) to each target, resumably (docs/convert.md).

    Round robin over the fit sets; interrupt at any time and run the same command
    again to go on.  Runs sharing --out share the work (each conversion is claimed).
    """
    from pathlib import Path

    from rich.markup import escape

    from types import SimpleNamespace

    from .conversion import table

    _no_stdout(out, "convert-table appends its rows to a file as they finish")
    targets = [t.strip() for t in to.split(",") if t.strip()]
    bad = [t for t in targets if t not in table.TARGETS]
    if bad:
        _fail(f"--to: the table's targets are {', '.join(table.TARGETS)}, got {', '.join(bad)}")
    fits_ = [f.strip() for f in fits.split(",") if f.strip()] if fits else None
    from .plotting import check_writable_file

    try:    # before the work (22 s of it before the first row): outputs that cannot be written fail now
        check_writable_file(out, "--out")
        if md is not None:
            check_writable_file(md, "--markdown")
    except ValueError as e:
        _fail(str(e))

    def on_row(r):
        if "error" in r:
            console.print(f"[red]failed[/red] {escape(table.key(r))}: {escape(r['error'])}", soft_wrap=True)
        else:
            flip, ratio = _looks_cells(SimpleNamespace(**r) if "flip" in r else None)
            console.print(f"{escape(table.key(r))} {r['target']} "
                          + " / ".join(f"{d:.3f}" for d in r["albedo_diff"]) + f" FLIP {flip} highlight {ratio}"
                          + f" {r['seconds']:.1f} s", soft_wrap=True)
            for w in r.get("looks_warnings", ()):
                click.echo(f"warning: {table.key(r)}: {w}", err=True)

    problems, runs = [], []
    try:
        rows = table.run_table(out, targets, per_set=per_set, fits=fits_, limit=limit, workers=workers,
                               on_row=on_row, redo=[t.strip() for t in (redo or "").split(",") if t.strip()],
                               scheduler=scheduler, problems=problems, summary=runs)
    except KeyboardInterrupt:
        console.print(f"[yellow]interrupted[/yellow]: the finished rows are in {escape(out)}; "
                      "run the same command again to resume", soft_wrap=True)
        sys.exit(130)
    except ValueError as e:
        _fail(_scheduler_flag(e).replace("fits: ", "--fits: ").replace("workers ", "--workers ")
              .replace("redo: ", "--redo: "))
    for b in problems:
        what = "dropped a duplicated row" if "a second row of" in b else "skipped a damaged line"
        console.print(f"[yellow]{what}[/yellow] {escape(b)}", soft_wrap=True)
    for s in runs:
        _shared_note(s, "conversions", out)
    all_jobs = table.jobs(targets, per_set, fits_)
    console.print(f"{escape(out)}: {sum(table.key(j) in rows for j in all_jobs)} of {len(all_jobs)} conversions",
                  soft_wrap=True)
    if md is not None:
        write_atomic(md, table.markdown(rows))
        console.print(f"wrote {escape(md)} ({len(rows)} rows)")


@main.command("fit-batch")
@click.argument("targets", nargs=-1, required=True)
@click.option("--models", required=True, metavar="A,B,...", help="Models to fit (comma-separated registry names).")
@click.option("--metrics", default="perceptual", show_default=True, metavar="A,B,...",
              help="Metrics (comma-separated: perceptual, l2-cos, log).")
@click.option("--out", required=True, type=click.Path(file_okay=False),
              help="Results folder: OUT/fits/MODEL.csv, one row per fit, appended as fits finish.")
@click.option("--scheduler", metavar="ADDRESS", help="A running Dask scheduler (tcp://host:8786); "
              "default: local worker processes.")
@click.option("--workers", type=click.IntRange(0), help="Local worker processes (default: all cores; 0: "
              "no Dask, one fit after another).")
@click.option("--starts", type=click.IntRange(1), default=4, show_default=True, help="Optimiser starts per fit.")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(0),
              help="Seed of the random starts (the same for every fit).")
@click.option("--time-limit", type=_FiniteRange(0), help="Seconds per fit (best point so far).")
@click.option("--retry-failed", is_flag=True, help="Run again the fits recorded as failed.")
@click.option("--report", "report", type=click.Path(file_okay=False), help="Write the comparison report here.")
@click.option("--spheres", multiple=True, metavar="TARGET",
              help="Targets whose spheres (target and fits) the report renders (repeatable; default: the first).")
def fit_batch_cmd(targets, models, metrics, out, scheduler, workers, starts, seed, time_limit, retry_failed,
                  report, spheres):
    """Fit several MODELS to several TARGETS under several METRICS (Dask), resumably.

    TARGETS: model specs, MERL .binary files or CSV tables. Fits already in OUT
    are skipped, so an interrupted batch resumes where it stopped.
    """
    from rich.markup import escape

    from .fitting import batch
    from .fitting.batch_report import write_report

    _no_stdout(out, "fit-batch writes a results folder (OUT/fits/MODEL.csv)")
    models_ = [m.strip() for m in models.split(",") if m.strip()]
    metrics_ = [m.strip() for m in metrics.split(",") if m.strip()]
    bad = []
    try:
        todo = batch.plan(targets, models_, metrics_, out=out, seed=seed, starts=starts,
                          time_limit=time_limit, retry_failed=retry_failed, problems=bad)
    except ValueError as e:
        _fail(str(e))
    if spheres:             # was ignored: the report drew no sphere for a name it does not know
        known = set(targets) | {r["target"] for r in batch.load_results(out)}    # this run's and the folder's
        unknown = [s for s in spheres if s not in known]
        if unknown:
            _fail(f"--spheres: {', '.join(map(repr, unknown))} is not one of the TARGETS ({', '.join(targets)}) "
                  f"nor fitted in {out}")
    if report:              # its folder made before the fits (an unwritable one was refused only after them)
        from pathlib import Path

        Path(report).mkdir(parents=True, exist_ok=True)
    for b in bad:       # malformed rows: skipped (their fits run again), the good rows kept
        console.print(f"[yellow]skipped a malformed row[/yellow] {escape(b)}", soft_wrap=True)
    failed = [0]

    def on_result(row):
        if row["status"] != "ok":
            failed[0] += 1
            console.print(f"[red]failed[/red] {escape(row['target'])} / {row['model']} / {row['metric']}: "
                          f"{escape(str(row['error']))}")

    bar = _BatchBar(failed)
    console.print(f"fit-batch: {len(todo)} fits to run ({scheduler or 'local processes'})")
    try:
        with bar:
            s = batch.fit_batch(targets, models_, metrics_, out, scheduler=scheduler, workers=workers, seed=seed,
                                starts=starts, time_limit=time_limit, retry_failed=retry_failed,
                                progress=bar, on_result=on_result)
    except KeyboardInterrupt:
        console.print(f"[yellow]interrupted[/yellow]: the finished fits are in {escape(out)}; "
                      "run the same command again to resume", soft_wrap=True)
        sys.exit(130)
    except ValueError as e:     # the folder cannot be written (read-only, disk full): what is kept, how to resume
        _fail(_scheduler_flag(e))   # or the scheduler cannot be reached
    _shared_note(s, "fits", out)
    if s.dashboard:
        console.print(f"Dask dashboard: {s.dashboard}")
    console.print(f"{s.done} fits done ({s.failed} failed), {s.skipped} already in {escape(out)}, "
                  f"{s.seconds:.1f} s on {s.workers} workers", soft_wrap=True)
    if report:
        first = [t for t in targets][:1]
        p = write_report(out, report, spheres=list(spheres) or first)
        console.print(f"wrote {escape(str(p))}")
    if s.failed:            # every fit that could run is written; the failed ones are rows with their error
        raise SystemExit(1)


def _no_stdout(out, what):
    """Refuse ``--out -`` of a command that writes files (it cannot write to standard output)."""
    if out == "-":
        _fail(f"--out -: {what}, which cannot go to standard output; give a path")


def _scheduler_flag(e) -> str:
    """A library error's text with the ``scheduler:`` argument named by its flag."""
    from .engine import SchedulerError

    return "--scheduler: " + str(e).split(": ", 1)[1] if isinstance(e, SchedulerError) else str(e)


def _shared_note(s, what, out):
    """Say which tasks were left to another run on the same output (and whose claims they are),
    and which stale claims were taken over."""
    from rich.markup import escape

    for t in s.taken_over:
        console.print(f"[yellow]took over a stale claim[/yellow] {escape(t)}", soft_wrap=True)
    if s.shared:
        owners = sorted(set(s.left_to.values()))
        by = f" (claimed by {', '.join(owners[:3])}{' ...' if len(owners) > 3 else ''})" if owners else ""
        console.print(f"{s.shared} {what} left to another run on {escape(str(out))}{escape(by)}", soft_wrap=True)


class _BatchBar:
    """The fit-batch progress bar (counts, failures, time left), stopped on every exit."""

    def __init__(self, failed):
        self.failed = failed
        self.prog = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.prog is not None:
            self.prog.stop()
        return False

    def __call__(self, total, label=""):
        from rich.progress import MofNCompleteColumn, TimeRemainingColumn

        if not console.is_terminal:
            return lambda: None
        self.prog = Progress(TextColumn("fits"), BarColumn(), MofNCompleteColumn(),
                             TextColumn("{task.fields[failed]} failed"), TimeElapsedColumn(),
                             TimeRemainingColumn(), console=console, transient=True)
        self.prog.start()
        task = self.prog.add_task("fits", total=total, failed=0)

        def tick(n=1):
            self.prog.update(task, advance=n, failed=self.failed[0])

        return tick


@main.command()
@click.option("--port", type=click.IntRange(1, 65535), default=8765, show_default=True, help="Port to listen on.")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to bind (127.0.0.1 by default, also when empty; naming another address exposes the "
                   "explorer to the network, and says so).")
@click.option("--no-browser", is_flag=True, help="Do not open the page in a browser.")
def explore(port, host, no_browser):
    """Interactive BRDF explorer in the browser (lit sphere, lobes, albedo, verdict, exports)."""
    from .explorer import bind, resolve_host, serve, url_of

    host, exposed = resolve_host(host)  # '' is loopback; only a named address exposes the explorer
    try:
        sock = bind(host, port)         # before the URL is announced: a busy port fails here
    except ValueError as e:       # the library's "host:" / "choose another port" said as the options
        _fail(str(e).replace("(host: ", "(--host: ").replace("choose another port", "choose another --port"))
    if exposed:
        console.print(f"[bold red]WARNING: --host {host} makes the explorer reachable from the network: other "
                      f"machines can connect to port {port} (leave --host out for this machine only)[/]", soft_wrap=True)
    console.print(f"plausible explorer on {url_of(host, port)} (Ctrl-C to stop)", soft_wrap=True)
    try:
        serve(host=host, port=port, open_browser=not no_browser, sock=sock)
    except KeyboardInterrupt:
        pass


@main.command()
@click.option("--out", default="out", show_default=True, type=click.Path(file_okay=False), callback=_folder_out,
              help="Directory for the images, data and index.html.")
@click.option("--only", "only", multiple=True, metavar="NAME", help="Make only this figure (repeatable).")
@click.option("--spp", type=click.IntRange(1, 1 << 16), help="Samples per pixel of the renders (default 128).")
@click.option("--resolution", type=click.IntRange(8, 8192), help="Base image size in pixels (default 320).")
@click.option("--quick", is_flag=True, help="Small images and sample counts (the CI mode).")
@click.option("--force", is_flag=True, help="Remake figures even when their inputs have not changed.")
@click.option("--list", "list_only", is_flag=True, help="List the figures and exit.")
@click.option("--jobs", type=click.IntRange(1, 64), metavar="N",
              help="Worker processes making figures side by side (default: the cores available, at most 2).")
@VARIANT_OPT
def figures(out, only, spp, resolution, quick, force, list_only, jobs):
    """Reproduce the papers' figures as a browsable report (OUT/index.html).

    Exits with status 1 when a figure fails or a measured check does not hold.
    """
    from . import figures as F

    if list_only:
        for n in F.names():
            click.echo(f"{n:28s} {F.get(n).title}")
        return
    from .plotting import check_writable_dir

    try:    # unknown names and an unwritable folder fail before anything is made
        only = list(dict.fromkeys(F.get(n).name for n in only))
        check_writable_dir(out, "--out", create=True)
        res = F.run(out, only=only or None, spp=spp, resolution=resolution, quick=quick, force=force,
                    console=console, progress=_bar(), jobs=jobs or _default_jobs())
    except ValueError as e:
        _fail(str(e))
    failed = [n for n, m in res.items() if m["status"] != "ok"]
    red = [f"{n}: {x['quantity']}" for n, m in res.items() for x in m.get("measurements", [])
           if x.get("ok") is False]
    if failed:
        click.echo(f"figures that failed: {', '.join(failed)}", err=True)
    if red:
        click.echo(f"measured checks that do not hold ({len(red)}): {'; '.join(red)}", err=True)
    sys.exit(1 if failed or red else 0)


@main.command("export")
@click.argument("model")
@PARAM_OPT
@click.option("--format", "fmt", type=click.Choice(["glsl", "brdf", "js"]), default="glsl", show_default=True,
              help="glsl: a GLSL ES 3.00 function plausible_f(wi, wo); brdf: a Disney BRDF Explorer file; "
                   "js: an ES module for three.js / WebGL2 (GLSL, uniforms' values, tables as textures).")
@click.option("--out", required=True, type=click.Path(dir_okay=False, allow_dash=True),
              help="File to write; - writes to standard output.")
@click.option("--uniforms", is_flag=True, help="glsl: parameters as uniforms instead of constants.")
@click.option("--prefix", default="plausible", show_default=True, metavar="NAME",
              help="glsl, js: prefix of the exported names (NAME_f, NAME_pdf, uniforms NAME_n), so that "
                   "several exports share one shader.")
@click.option("--table-limit", type=click.IntRange(min=1), default=None, metavar="N",
              help="brdf: resample tables of more than N values (default 1200; the file states the "
                   "interpolation error).")
def export_cmd(model, params, fmt, out, uniforms, prefix, table_limit):
    """Export MODEL as a shader (see docs/export.md)."""
    from .export import BRDF_TABLE_LIMIT, check_prefix, write

    try:
        check_prefix(prefix, "--prefix")
    except ValueError as e:
        _fail(str(e))
    m = _model(model, params)
    try:
        text = write(m, fmt, None if out == "-" else out, uniforms=uniforms, prefix=prefix,
                     table_limit=table_limit or BRDF_TABLE_LIMIT)
    except ValueError as e:
        _fail(str(e))
    except OSError as e:
        _fail(f"cannot write {out}: {e.strerror}")
    if out == "-":          # the text alone on stdout (pipe it); the note on stderr
        click.echo(text, nl=False)
        click.echo(f"wrote standard output ({fmt}, {m!r})", err=True)
    else:
        click.echo(f"wrote {out} ({fmt}, {m!r})")


@main.command()
@click.option("--fit", "fit", metavar="FIT", help="Only this fit set and its materials.")
@click.option("--fits", "fits_only", is_flag=True, help="List only the fit sets.")
@click.option("--json", "as_json", is_flag=True, help="Print the fit sets and materials as JSON.")
def materials(fit, fits_only, as_json):
    """The published fits of the MERL materials (Ngan et al. 2005, Löw et al. 2012):
    fit sets, then every material with its fits.  Use one as material:NAME@FIT.
    A fit set that cannot be loaded is marked in the first table and left out
    of the materials' lists."""
    from . import catalogue as library

    try:
        sets = [library.fit_set(fit)] if fit else library.fits()
        mats = library.materials(fit)
    except ValueError as e:
        _fail(str(e))
    loadable = {fs.key for fs in library.fits() if fs.built}
    mats = {name: tuple(k for k in keys if k in loadable) for name, keys in mats.items()}
    mats = {name: keys for name, keys in mats.items() if keys}
    if as_json:
        out = dict(fits=[dict(key=fs.key, model=fs.model, materials=len(library.fit_data(fs.key)),
                              description=fs.description, loadable=fs.built, reason=fs.reason or None)
                         for fs in sets])
        if not fits_only:
            out["materials"] = {name: list(keys) for name, keys in mats.items()}
        return _echo_json(out)
    t = Table(title="published fit sets (use as material:NAME@FIT)")
    for col in ("fit", "bbm model", "materials", "what it is"):
        t.add_column(col)
    for fs in sets:
        what = fs.description if fs.built else f"[red]not loadable:[/red] {escape(fs.reason)}"
        t.add_row(fs.key, fs.model, str(len(library.fit_data(fs.key))), what)
    console.print(t)
    if fits_only:
        return
    if fit and fit not in loadable:
        _fail(f"fit {fit!r} cannot be loaded: {library.fit_set(fit).reason}")
    t = Table(title=f"materials ({len(mats)})" + (f" of {fit}" if fit else ""))
    t.add_column("material", style="bold", no_wrap=True)
    t.add_column("fits")
    for name, keys in mats.items():
        t.add_row(name, ", ".join(keys))
    console.print(t)


if __name__ == "__main__":  # pragma: no cover
    main()
