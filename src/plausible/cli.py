"""The ``plausible`` command line: a thin layer over the library."""

from __future__ import annotations

import math
import sys

import click
import numpy as np
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from . import registry
from .analysis import albedo_curve, check as run_check, direction

console = Console()


def _fail(msg):
    raise click.UsageError(msg)


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
    if not (0 <= t <= 180) or not math.isfinite(p):
        _fail(f"{what}: theta must lie in [0, 180] degrees, got {t}")
    return direction(math.radians(t), math.radians(p))


class _Bar:
    """Progress bar usable as the ``progress`` callback of the analysis functions."""

    def __init__(self, label, enabled=True):
        self.label = label
        self.enabled = enabled and console.is_terminal

    def __call__(self, total):
        if not self.enabled:
            return lambda: None
        self.prog = Progress(TextColumn(self.label), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                             TimeElapsedColumn(), console=console, transient=True)
        self.prog.start()
        task = self.prog.add_task(self.label, total=total)

        def tick():
            self.prog.advance(task)
            if self.prog.tasks[0].finished:
                self.prog.stop()

        return tick


PARAM_OPT = click.option("-p", "--param", "params", multiple=True, metavar="NAME=VALUE",
                         help="Model parameter (repeatable); colours as r,g,b.")


@click.group(context_settings=dict(help_option_names=["-h", "--help"]))
@click.version_option(package_name="plausible")
def main():
    """Physically plausible reflection models of the Phong family.

    Evaluate, sample, verify and plot the models of Ashikhmin & Shirley (2000),
    Neumann, Neumann & Szirmay-Kalos (1999) and Lafortune & Willems (1994).
    """


@main.command()
def models():
    """List every registered model with its parameters, defaults and ranges."""
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
        t.add_row(name, ps, desc)
    console.print(t)


def _fmt(v):
    if isinstance(v, (list, tuple)):
        return ",".join(f"{x:g}" if isinstance(x, float) else str(x) for x in v)
    return f"{v:g}" if isinstance(v, float) else str(v)


@main.command("eval")
@click.argument("model")
@PARAM_OPT
@click.option("--wi", required=True, metavar="THETA_DEG,PHI_DEG", help="Direction wi (to the light).")
@click.option("--wo", required=True, metavar="THETA_DEG,PHI_DEG", help="Direction wo (to the viewer).")
def eval_cmd(model, params, wi, wo):
    """Print the BRDF value f(wi, wo) (no cosine factor)."""
    m = _model(model, params)
    f = m.eval(_angles(wi, "--wi"), _angles(wo, "--wo"))
    click.echo(" ".join(f"{x:.10g}" for x in np.atleast_1d(f)))


@main.command()
@click.argument("model", required=False)
@PARAM_OPT
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@click.option("--all", "all_models", is_flag=True,
              help="Check every registered model on its defaults and extreme parameters.")
@click.option("--quick", is_flag=True, help="Fewer directions and samples.")
def check(model, params, as_json, all_models, quick):
    """Verify reciprocity, energy conservation, sampling consistency and chi-square.

    Exits with status 1 when a property fails.
    """
    from .analysis.suite import model_variants

    if not model and not all_models:
        _fail("give a MODEL or --all")
    if all_models:
        targets = [m for name in registry.names() for m in model_variants(name)]
    else:
        targets = [_model(model, params)]
    reports = []
    for m in targets:
        rep = run_check(m, quick=quick, progress=_Bar(f"check {m.name}", not as_json))
        reports.append(rep)
        if not as_json:
            _print_report(rep)
    if as_json:
        import json

        click.echo(json.dumps([r.to_dict() for r in reports] if all_models else reports[0].to_dict(), indent=1))
    if all_models:   # the implausible baselines may fail what they do not claim
        sys.exit(0 if all(r.as_claimed(m.info) for r, m in zip(reports, targets)) else 1)
    sys.exit(0 if reports[0].passed else 1)


def _print_report(rep):
    t = Table(title=f"{rep.model} {rep.params}", title_justify="left")
    for c in ("property", "figure", "bound", "verdict", "worst case"):
        t.add_column(c, overflow="fold")
    for row in rep.rows():
        style = "green" if row[3] == "PASS" else "red"
        t.add_row(*row[:3], f"[{style}]{row[3]}[/{style}]", row[4])
    console.print(t)


@main.command()
@click.argument("models", nargs=-1, required=True)
@PARAM_OPT
@click.option("--plot", type=click.Path(dir_okay=False), help="Write the curves to this image file.")
@click.option("--phi", default=0.0, show_default=True, help="Azimuth of incidence (degrees).")
@click.option("-n", "--points", default=46, show_default=True, help="Number of incidence angles.")
def albedo(models, params, plot, phi, points):
    """Directional albedo against incidence angle, for one or more models.

    MODELS are names with optional parameters, e.g. reciprocal-phong:n=150
    ashikhmin-shirley:nu=10:nv=10:rs=1:rd=0 (-p applies to every model).
    """
    from .plotting import default_thetas, plot_albedo_curves

    th = default_thetas(points)
    targets = [_model(spec, params) for spec in models]
    tick = _Bar("albedo")(len(targets) * len(th))
    curves = [(repr(m), th, albedo_curve(m, th, math.radians(phi), progress=tick)) for m in targets]
    t = Table(title="directional albedo")
    t.add_column("theta (deg)")
    for label, _, _ in curves:
        t.add_column(label, overflow="fold")
    for i, x in enumerate(th):
        t.add_row(f"{math.degrees(x):.2f}", *[_fmt_alb(r.value[i], r.error[i]) for _, _, r in curves])
    console.print(t)
    if plot:
        plot_albedo_curves(curves, plot)
        console.print(f"wrote {plot}")


def _fmt_alb(v, e):
    v = np.atleast_1d(v)
    e = np.atleast_1d(e)
    return " ".join(f"{a:.6f}" for a in v) + f" (+-{float(np.max(e)):.1e})"


# -- fit (plausible.fitting) ------------------------------------------------------------
@main.command("fit")
@click.argument("model")
@click.option("--target", required=True, metavar="FILE_OR_MODEL",
              help="A model spec (name:k=v), a MERL .binary file or a CSV table (wi xyz, wo xyz, f).")
@PARAM_OPT
@click.option("--metric", type=click.Choice(["perceptual", "l2-cos", "log"]), default="perceptual",
              show_default=True, help="Error metric minimised (see docs/fitting.md).")
@click.option("--out", type=click.Path(file_okay=False), help="Write plane.png, albedo.png, fit.json here.")
@click.option("--starts", type=click.IntRange(1), default=4, show_default=True, help="Optimiser starts.")
@click.option("--time-limit", type=click.FloatRange(0), help="Stop after this many seconds (best so far).")
@click.option("--seed", default=0, show_default=True, help="Seed of the random starts.")
def fit_cmd(model, target, params, metric, out, starts, time_limit, seed):
    """Fit MODEL's parameters to a target; -p fixes parameters of MODEL."""
    from .fitting import fit as run_fit
    from .fitting.plots import write_plots

    try:
        res = run_fit(model, target, metric, fixed=registry.parse_assignments(params), starts=starts,
                      seed=seed, time_limit=time_limit, progress=_Bar(f"fit {model}"))
    except ValueError as e:
        _fail(str(e))
    console.print(f"[bold]{res.model.name}[/bold] fitted to {res.target.label} ({metric}, "
                  f"{res.evaluations} evaluations, {res.seconds:.1f} s)")
    t = Table()
    t.add_column("parameter"); t.add_column("value")
    for k, v in res.params.items():
        t.add_row(k, _fmt(v.tolist() if isinstance(v, np.ndarray) else v))
    console.print(t)
    e = Table()
    e.add_column("error (every metric)"); e.add_column("value")
    for k, v in res.errors.items():
        e.add_row(k, "n/a (no target albedo)" if v is None else f"{v:.6g}")
    console.print(e)
    if res.timed_out:
        console.print("[yellow]time limit reached: best point found so far[/yellow]")
    if out:
        for p in write_plots(res, out):
            console.print(f"wrote {p}")


@main.command()
@click.option("--out", default="out", show_default=True, type=click.Path(file_okay=False),
              help="Directory for the images, data and index.html.")
@click.option("--only", "only", multiple=True, metavar="NAME", help="Make only this figure (repeatable).")
@click.option("--spp", type=click.IntRange(1, 1 << 16), help="Samples per pixel of the renders (default 128).")
@click.option("--resolution", type=click.IntRange(8, 8192), help="Base image size in pixels (default 320).")
@click.option("--quick", is_flag=True, help="Small images and sample counts (the CI mode).")
@click.option("--force", is_flag=True, help="Remake figures even when their inputs have not changed.")
@click.option("--list", "list_only", is_flag=True, help="List the figures and exit.")
def figures(out, only, spp, resolution, quick, force, list_only):
    """Reproduce the papers' figures as a browsable report (OUT/index.html)."""
    from . import figures as F

    if list_only:
        for n in F.names():
            click.echo(f"{n:28s} {F.get(n).title}")
        return
    try:
        res = F.run(out, only=list(only) or None, spp=spp, resolution=resolution, quick=quick, force=force,
                    console=console)
    except ValueError as e:
        _fail(str(e))
    sys.exit(0 if all(m["status"] == "ok" for m in res.values()) else 1)


@main.command()
@click.option("--fit", "fit", metavar="FIT", help="List only the materials of this fit set.")
@click.option("--fits", "fits_only", is_flag=True, help="List only the fit sets.")
def materials(fit, fits_only):
    """The published fits of the MERL materials (Ngan et al. 2005, Löw et al. 2012):
    fit sets, then every material with its fits.  Use one as material:NAME@FIT."""
    from . import library

    t = Table(title="published fit sets (use as material:NAME@FIT)")
    for col in ("fit", "bbm model", "materials", "what it is"):
        t.add_column(col)
    for fs in library.fits():
        what = fs.description if fs.built else f"[red]not loadable:[/red] {fs.reason}"
        t.add_row(fs.key, fs.model, str(len(library.fit_data(fs.key))), what)
    console.print(t)
    if fits_only:
        return
    try:
        mats = library.materials(fit)
    except ValueError as e:
        _fail(str(e))
    t = Table(title=f"materials ({len(mats)})" + (f" of {fit}" if fit else ""))
    t.add_column("material", style="bold", no_wrap=True)
    t.add_column("fits")
    for name, keys in mats.items():
        t.add_row(name, ", ".join(keys))
    console.print(t)


if __name__ == "__main__":  # pragma: no cover
    main()
