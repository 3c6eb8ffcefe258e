"""The ``ftc-mc`` command line: parse, call the API (:mod:`ftc_mc.api`), print.

Every command turns a bad input (a :class:`~ftc_mc.errors.UserError`) into one
line on stderr naming the problem and exit code 2, without a traceback and
without writing anything.  Any other error is a bug and shows its traceback.
"""

from __future__ import annotations

import contextlib
import functools
import json
import shlex
import sys

import click

from .errors import UserError

TERMINAL_WIDTH = 120
"""Widest line of the table ``ftc-mc run`` prints (the full one is in summary.md)."""


def user_errors(func):
    """Turn :class:`UserError` into one line and exit code 2."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except UserError as exc:
            msg = str(exc).strip().splitlines()
            click.echo(f"ftc-mc: error: {msg[0] if msg else type(exc).__name__}",
                       err=True)
            sys.exit(2)
    return wrapper


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="ftc-mc")
def cli():
    """Monte Carlo fault injection for indirect active fault-tolerant control."""


@cli.command()
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@click.option("--airframe", metavar="NAME|PATH", help="A preset (see ftc-mc airframes), "
              "an airframe YAML file or a linear model .npz/.mat [default: "
              "the default preset].")
@click.option("--save", type=click.Path(dir_okay=False, writable=True),
              help="Write the linear model (A, B, C, trim, limits, dt, gust matrices) to "
              "this .npz or MATLAB .mat file; it can be flown with --airframe FILE "
              "(with --dof 6: the 6-DOF model and its airframe, lateral data included).")
@click.option("--export", type=click.Path(dir_okay=False, writable=True),
              help="Write the airframe's parameters to this YAML file (every field with "
              "its unit): edit it and fly it with --airframe FILE.yaml.")
@click.option("--airspeed", default=20.0, show_default=True, type=float,
              help="Trim airspeed [m/s].")
@click.option("--gamma", "gamma_deg", default=-3.0, show_default=True, type=float,
              help="Trim flight-path angle [deg].")
@click.option("--dt", default=0.1, show_default=True, type=float,
              help="Sampling period [s].")
@click.option("--dof", type=click.Choice(["3", "6"]), default="3", show_default=True,
              help="Degrees of freedom: 3 the longitudinal model (surge, heave, "
              "pitch), 6 the full rigid body with lateral-directional dynamics "
              "(trim and the named modes: short period, phugoid, roll, Dutch roll, "
              "spiral; needs an airframe with lateral data).")
@click.option("--trimmable", is_flag=True,
              help="With --dof 6: also the trimmable set of each elevon, the locks with "
              "a steady flight inside the default validity envelope, of the 6-DOF "
              "linear model (exact) and of the airframe's equations (a bisection of "
              "steady-flight searches, up to a minute or two the first time per "
              "airframe, then cached).")
@user_errors
def model(as_json, airframe, save, export, airspeed, gamma_deg, dt, dof, trimmable):
    """Trim point, named eigenvalues and redundancy check of the linear model."""
    from .io.atomic import atomic_path
    from .model.airframe_files import export_airframe
    from .model.presets import PRESETS, resolve_airframe
    from .model.source import DEFAULT_AIRFRAME, is_linear_model, load_plant
    from .model.summary import format_summary, model_summary, save_npz

    spec = airframe or DEFAULT_AIRFRAME
    if save is not None and not save.endswith((".npz", ".mat")):
        raise UserError(f"--save: file name must end in .npz or .mat, got {save!r}")
    suffix = None if save is None else save[save.rindex("."):]
    if export is not None and not export.endswith((".yaml", ".yml")):
        raise UserError(f"--export: file name must end in .yaml, got {export!r}")
    if export is not None and is_linear_model(spec):
        raise UserError(f"--export: {spec} is a linear model, it has no airframe "
                        "parameters to export")
    if trimmable and dof != "6":
        raise UserError("--trimmable: needs --dof 6 (a locked elevon is the 6-DOF "
                        "plant's fault)")
    if dof == "6":
        return _model_sixdof(spec, as_json, save, export, airspeed, gamma_deg, dt, suffix,
                             trimmable)
    plant = load_plant(spec, airspeed, gamma_deg, dt)
    summary = model_summary(plant) if plant.airframe is not None else None
    if save is not None:
        with atomic_path(save) as tmp, open(tmp, "wb") as f:
            save_npz(plant, f, suffix)
    if export is not None:
        source = str(PRESETS[spec].source) if spec in PRESETS else str(spec)
        with atomic_path(export) as tmp:
            export_airframe(resolve_airframe(spec), tmp, name=spec, source=source)
    if summary is None:
        click.echo(f"{spec}: a linear model (trim throttle {plant.u0[0]:.4f}, "
                   f"airspeed {plant.trim.V0:g} m/s, dt {plant.dt:g} s); it has no "
                   "equations to summarise")
    else:
        click.echo(json.dumps(summary, indent=2) if as_json else format_summary(summary))
    for what, path in (("linear model", save), ("airframe", export)):
        if path is not None and not as_json:
            click.echo(f"wrote the {what} to {path}")


def _model_sixdof(spec, as_json, save, export, airspeed, gamma_deg, dt, suffix,
                  trimmable=False):
    """``ftc-mc model --dof 6``: the 6-DOF trim and named modes (its own import
    path, so a longitudinal ``model`` never loads the 6-DOF kernels); with
    ``trimmable``, the trimmable sets (:func:`ftc_mc.model.trimmable.trimmable_summary`)."""
    from .io.atomic import atomic_path
    from .model.airframe_files import export_airframe
    from .model.presets import PRESETS, resolve_airframe
    from .model.sixdof import (build_sixdof_plant, format_sixdof_summary,
                               save_sixdof_npz, sixdof_summary)
    from .model.source import is_linear_model

    if is_linear_model(spec):
        raise UserError(f"--dof 6: {spec} is a linear model; the 6-DOF model needs an "
                        "airframe (a preset or an airframe .yaml with lateral data)")
    af = resolve_airframe(spec)
    plant = build_sixdof_plant(af, airspeed, gamma_deg, dt, where=f"airframe {spec}")
    summary = sixdof_summary(plant)
    if trimmable:
        from .cache.trimmable import cached_trimmable_sets
        from .model.trimmable import trimmable_summary

        summary["trimmable_set"] = trimmable_summary(
            plant, cached_trimmable_sets(plant.airframe, ("left", "right"), name=spec))
    source = str(PRESETS[spec].source) if spec in PRESETS else str(spec)
    if save is not None:
        with atomic_path(save) as tmp, open(tmp, "wb") as f:
            save_sixdof_npz(plant, f, source, suffix)
    if export is not None:
        with atomic_path(export) as tmp:
            export_airframe(af, tmp, name=spec, source=source)
    if as_json:
        click.echo(json.dumps(summary, indent=2))
    elif trimmable:
        from .model.trimmable import format_trimmable_summary

        click.echo(format_sixdof_summary(summary, spec) + "\n\n"
                   + format_trimmable_summary(summary["trimmable_set"]))
    else:
        click.echo(format_sixdof_summary(summary, spec))
    for what, path in (("6-DOF linear model", save), ("airframe", export)):
        if path is not None and not as_json:
            click.echo(f"wrote the {what} to {path}")


@cli.command()
@click.option("--airspeed", default=20.0, show_default=True, type=float,
              help="Trim airspeed [m/s].")
@click.option("--gamma", "gamma_deg", default=-3.0, show_default=True, type=float,
              help="Trim flight-path angle [deg].")
@user_errors
def airframes(airspeed, gamma_deg):
    """The airframe presets: their sources and trim points."""
    from .model.presets import list_airframes
    from .model.source import DEFAULT_AIRFRAME

    for row in list_airframes(airspeed, gamma_deg):
        mark = " (default)" if row["name"] == DEFAULT_AIRFRAME else ""
        click.echo(f"{row['name']}{mark}: {row['note']}")
        click.echo(f"    source: {row['source']}")
        click.echo(f"            {row['reference']}")
        if row["refused"]:
            click.echo(f"    trim at {airspeed:g} m/s, {gamma_deg:g} deg: {row['refused']}")
        else:
            click.echo(f"    trim at {airspeed:g} m/s, {gamma_deg:g} deg: throttle "
                       f"{row['throttle']:.3f}, alpha {row['alpha_deg']:.3f} deg, elevons "
                       f"{row['elevon_rad']:.4f} rad")


def _default_out(config_path: str, cfg=None):
    """``results/<config stem>``, or the first ``-N`` suffix that holds no run.

    The designs run beyond the signature variants, an airframe other than the
    default, and a truth plant other than the paper's (linear, still air), are
    named in the stem, e.g. ``results/paper_tables-x8-gryte2018-nonlinear-moderate``
    or ``results/paper_tables-gust_glr``.
    """
    from pathlib import Path

    from .io.lock import holder
    from .io.results import RUN_FILES

    from .model.source import DEFAULT_AIRFRAME, airframe_label

    stem = Path(config_path).stem
    custom = () if cfg is None else (
        cfg.campaign.designs if hasattr(cfg, "campaign") else
        [d for d in [cfg.scenario.design] if d is not None])
    if custom:
        stem += "-" + "-".join(custom)
    if cfg is not None and cfg.model.airframe != DEFAULT_AIRFRAME:
        stem += f"-{airframe_label(cfg.model.airframe)}"
    if cfg is not None and (cfg.plant.kind, cfg.plant.turbulence) != ("linear", "none"):
        stem += f"-{cfg.plant.kind}" + (f"-{cfg.plant.turbulence}"
                                        if cfg.plant.turbulence != "none" else "")
    if cfg is not None and cfg.plant.dof != 3:
        stem += f"-{cfg.plant.dof}dof"
    base = Path("results") / stem
    cand, n = base, 1
    while cand.exists() and (any((cand / f).exists() for f in RUN_FILES)
                             or (cand / ".chunks").exists() or holder(cand) is not None):
        n += 1
        cand = base.with_name(f"{base.name}-{n}")
    return cand


AIRFRAME_HELP = ("Airframe: a preset (see ftc-mc airframes), an airframe YAML file, or a "
                 "linear model .npz/.mat (overrides model.airframe).")


DESIGN_HELP = ("A design to run: paper, swapped or a key of the config's designs section "
               "(repeatable; replaces campaign.signature and campaign.designs).")


def plant_options(func):
    """``--airframe``, ``--plant``, ``--turbulence`` and ``--dof`` of ``run``,
    ``sweep``, ``endurance`` and ``scenario``."""
    func = click.option("--airframe", metavar="NAME|PATH", help=AIRFRAME_HELP)(func)
    func = click.option("--dof", type=click.Choice(["3", "6"]), default=None,
                        callback=lambda _c, _p, v: None if v is None else int(v),
                        help="Degrees of freedom of the truth plant: 3 (longitudinal) or "
                        "6 (the flying wing with its lateral motion and a lateral "
                        "autopilot; overrides plant.dof).")(func)
    func = click.option("--turbulence",
                        type=click.Choice(["none", "light", "moderate", "severe"]),
                        help="MIL-F-8785C Dryden gusts on the truth plant (overrides "
                        "plant.turbulence).")(func)
    return click.option("--plant", type=click.Choice(["linear", "nonlinear"]),
                        help="Truth plant: the linear model of eq. (1) or the nonlinear "
                        "X8 (overrides plant.kind; the estimator stays linear).")(func)


def parallel_options(func):
    """``--backend``, ``--scheduler`` and ``--quiet`` of ``run`` and ``sweep``."""
    func = click.option("--quiet", is_flag=True, help="No progress bar.")(func)
    func = click.option("--scheduler", help="Dask scheduler address, e.g. "
                        "tcp://10.0.0.5:8786 [default: a local cluster].")(func)
    return click.option("--backend", type=click.Choice(["threads", "loky", "dask"]),
                        default="threads", show_default=True,
                        help="Workers: threads in this process (the kernels release the "
                        "GIL), worker processes here (loky), or a Dask cluster.")(func)


@contextlib.contextmanager
def _interruptible(out_dir):
    """SIGINT (Ctrl-C) or SIGTERM stops the command: one line says what is kept and
    how to continue, and the process ends with 130 or 143 at once
    (:mod:`ftc_mc.interrupt`; a second signal ends it at once, too)."""
    from .interrupt import exit_code, hard_exit, stop_on_signals
    from .io.chunks import FOLDER, ChunkStore

    with stop_on_signals():
        try:
            yield
        except KeyboardInterrupt as exc:
            folder = out_dir / FOLDER
            what = signal_name(exc)
            if (folder / "manifest.json").exists():
                n = len(ChunkStore(out_dir, "").finished())
                click.echo(f"\ninterrupted ({what}): {n} finished chunk(s) kept in {folder}; "
                           f"continue with: {resume_command(out_dir)}", err=True)
            elif any((out_dir / f).exists() for f in ("summary.md", "sweep.md")):
                click.echo(f"\ninterrupted ({what}) after the results were written to "
                           f"{out_dir}", err=True)
            else:
                click.echo(f"\ninterrupted ({what}) before any chunk was finished; "
                           "nothing to resume", err=True)
            hard_exit(exit_code(exc))


def signal_name(exc: BaseException) -> str:
    """``SIGINT`` or ``SIGTERM``: the signal behind an interrupt."""
    from .interrupt import Interrupted

    return str(exc) if isinstance(exc, Interrupted) else "SIGINT"


def resume_command(out_dir) -> str:
    """The command line that continues this one: its own arguments without
    ``--out``, ``--overwrite`` and ``--resume``, then ``--resume --out DIR``."""
    args, skip = [], False
    for a in sys.argv[1:]:
        if skip:
            skip = False
        elif a == "--out":
            skip = True
        elif not (a.startswith("--out=") or a in ("--overwrite", "--resume")):
            args.append(a)
    return shlex.join(["ftc-mc", *args, "--resume", "--out", str(out_dir)])


def terminal_table(summary) -> str:
    """The run summary as a Markdown table of at most :data:`TERMINAL_WIDTH` columns.

    Per transition and variant: trials judged, inappropriate and no-reset
    rates, the share of no-reset trials explained by a small ``b1`` or a lock
    near trim, the median reset delay, and the paper's counts of inappropriate
    and no-reset trials (of 1000; ``-`` in the right elevon's rows, which the
    paper did not run).  The full table, with 95 % intervals and the
    ``correct_side`` rate, is in ``summary.md``.
    """
    import math

    def paper(r):
        i, nr = r["paper_inappropriate"], r["paper_no_reset"]
        return f"{int(i)} / {int(nr)}" if math.isfinite(i) and math.isfinite(nr) else "-"

    def num(x, fmt):
        return "-" if not math.isfinite(x) else fmt.format(x)

    head = ("transition", "variant", "judged", "inappr. %", "no reset %", "explained",
            "delay med [s]", "paper inap/nr")
    rows = [(r["transition"], r["variant"], str(r["trials"]),
             num(100 * r["inappropriate_rate"], "{:.1f}"),
             num(100 * r["no_reset_rate"], "{:.1f}"),
             num(100 * r["no_reset_explained_share"], "{:.0f} %"),
             num(r["delay_median_s"], "{:.1f}"),
             paper(r))
            for _, r in summary.iterrows()]
    widths = [max(len(c) for c in col) for col in zip(head, *rows)]

    def line(cells):
        return "| " + " | ".join(c.ljust(w) if i < 2 else c.rjust(w)
                                 for i, (c, w) in enumerate(zip(cells, widths))) + " |"

    rule = "|" + "|".join(":" + "-" * (w + 1) if i < 2 else "-" * (w + 1) + ":"
                          for i, w in enumerate(widths)) + "|"
    return "\n".join([line(head), rule, *map(line, rows)])


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--trials", type=int, help="Trials per transition (overrides the config).")
@click.option("--seed", type=int, help="Root seed (overrides the config).")
@click.option("--jobs", type=int, default=-1, show_default=True,
              help="Workers; -1: every core (one for a small run on worker processes). "
              "Results do not depend on it.")
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>, never reused].")
@click.option("--signature", type=click.Choice(["paper", "swapped", "both"]),
              help="Table 1 variant(s) (overrides the config).")
@click.option("--design", "design", multiple=True, metavar="NAME", help=DESIGN_HELP)
@click.option("--controller", type=click.Choice(["nominal", "reconfiguring", "lock_turn",
                                                "lock_turn_selected"]),
              help="Controller in the loop (overrides the config's controller.kind; a "
                   "design that sets its own controller keeps it).")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted run in --out, skipping its finished chunks.")
@click.option("--reset-log", metavar="all|none|first-N",
              help="Resets written to resets.parquet: all (the default), none, or the "
              "first N of each trial; trials.parquet and the summary do not depend on "
              "it (overrides campaign.reset_log).")
@click.option("--record", type=click.Choice(["none", "signals"]),
              help="signals: write every step of every trial and design to signals/ "
              "beside the tables, for scoring your own detector (ftc-mc score) "
              "(overrides campaign.record).")
@plant_options
@parallel_options
@user_errors
def run(config, trials, seed, jobs, out, signature, design, controller, overwrite, resume,
        reset_log, record, backend, scheduler, quiet, plant, turbulence, dof, airframe):
    """Run a Monte Carlo campaign (the paper's Tables 2-3) from CONFIG."""
    from pathlib import Path

    from . import api

    cfg = api.campaign_config(config, trials=trials, seed=seed, signature=signature,
                              controller=controller, plant=plant, turbulence=turbulence, dof=dof,
                              airframe=airframe, design=list(design) or None,
                              reset_log=reset_log, record=record)
    if resume and not out:
        raise UserError("--resume: name the run's directory with --out")
    out_dir = Path(out) if out else _default_out(config, cfg)
    with _interruptible(out_dir):
        result = api.run_campaign(cfg, jobs=jobs, progress=not quiet, backend=backend,
                                  scheduler=scheduler, out=out_dir, overwrite=overwrite,
                                  resume=resume,
                                  command=shlex.join(["ftc-mc", "run", config]))
    if result is None:
        click.echo(f"{out_dir}: the run is already complete; nothing to resume")
        return
    from .campaign.summary import actuator_rows, sensor_markdown_table
    acts = actuator_rows(result.summary)
    if len(acts):
        click.echo(terminal_table(acts))
    sensor = sensor_markdown_table(result.summary, intervals=False)
    if sensor:
        click.echo(("\n" if len(acts) else "") + "Sensor faults: what the FTC scheme "
                   "does with them (% of judged trials)\n" + sensor)
    click.echo(f"\nwrote {out_dir}/: trials.parquet, resets.parquet, summary.parquet, "
               "summary.md (the full table)"
               + (", signals/" if result.config.campaign.record == "signals" else ""))


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>, never reused].")
@click.option("--seed", type=int, help="Noise seed (overrides the config).")
@click.option("--design", metavar="NAME", help="The design to fly: paper, swapped or a "
              "key of the config's designs section (overrides scenario.signature and "
              "scenario.design).")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@plant_options
@user_errors
def scenario(config, out, seed, design, overwrite, plant, turbulence, dof, airframe):
    """Run the closed-loop scenario of CONFIG (the paper's Table 4 by default)."""
    from pathlib import Path

    from . import api
    from .scenario import summary_markdown

    sc = api.scenario_config(config, plant=plant, turbulence=turbulence, dof=dof, airframe=airframe,
                             design=design)
    out_dir = Path(out) if out else _default_out(config, sc)
    res = api.run_scenario(sc, seed=seed, out=out_dir, overwrite=overwrite,
                           command=shlex.join(["ftc-mc", "scenario", config]))
    files = [*api.SCENARIO_OUTPUTS, *sorted(p.name for p in out_dir.glob("fig*.png"))]
    click.echo(summary_markdown(res))
    click.echo(f"wrote {out_dir}/: " + ", ".join(files))


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--thresholds", help="t_q = t_nx values: start:stop:step or a,b,c.")
@click.option("--tq", help="t_q values (a grid with --tnx).")
@click.option("--tnx", help="t_nx values (a grid with --tq).")
@click.option("--transitions", help="Comma list of transitions (overrides the config).")
@click.option("--signature", type=click.Choice(["paper", "swapped", "both"]),
              help="Table 1 variant(s) (overrides the config).")
@click.option("--design", "design", multiple=True, metavar="NAME", help=DESIGN_HELP)
@click.option("--trials", type=int, help="Trials per transition (overrides the config).")
@click.option("--flights", type=int, help="Fault-free flights per point [default: trials].")
@click.option("--jobs", type=int, default=-1, show_default=True,
              help="Workers; -1: every core. Results do not depend on it.")
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>, never reused].")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted sweep in --out, skipping its finished chunks.")
@plant_options
@parallel_options
@user_errors
def sweep(config, thresholds, tq, tnx, transitions, signature, design, trials, flights, jobs,
          out, overwrite, resume, backend, scheduler, quiet, plant, turbulence, dof, airframe):
    """Sweep the Table 1 thresholds: Tables 2-3 and false resets per flight hour."""
    from pathlib import Path

    from . import api
    from .campaign.sweep import sweep_markdown

    cfg = api.campaign_config(config, trials=trials, signature=signature,
                              transitions=transitions, plant=plant, turbulence=turbulence, dof=dof,
                              airframe=airframe, design=list(design) or None)
    if resume and not out:
        raise UserError("--resume: name the sweep's directory with --out")
    out_dir = Path(out) if out else _default_out(config, cfg)
    with _interruptible(out_dir):
        res = api.run_sweep(cfg, thresholds, tq=tq, tnx=tnx, flights=flights, jobs=jobs,
                            progress=not quiet, backend=backend, scheduler=scheduler,
                            out=out_dir, overwrite=overwrite, resume=resume,
                            command=shlex.join(["ftc-mc", "sweep", config]))
    if res is None:
        click.echo(f"{out_dir}: the sweep is already complete; nothing to resume")
        return
    click.echo(sweep_markdown(res))
    click.echo(f"wrote {out_dir}/: sweep.parquet, sweep.md")


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--hours", required=True, metavar="H",
              help="Fault-free flight hours to fly (finite, > 0; rounded up to whole flights).")
@click.option("--flight-s", "flight_s", type=str, metavar="S",
              help="Length of each flight [s] [default: timing.duration_s]; longer than "
              "the filters' start-up.")
@click.option("--seed", type=int, help="Root seed of the flights (overrides the config).")
@click.option("--signature", type=click.Choice(["paper", "swapped", "both"]),
              help="Table 1 variant(s) (overrides the config).")
@click.option("--design", "design", multiple=True, metavar="NAME", help=DESIGN_HELP)
@click.option("--jobs", type=int, default=-1, show_default=True,
              help="Workers; -1: every core. Results do not depend on it.")
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>-endurance, never reused].")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted endurance run in --out, skipping its finished "
              "chunks.")
@click.option("--record", type=click.Choice(["none", "signals"]),
              help="signals: write every step of every flight and design to signals/ "
              "beside the tables, for scoring your own detector (ftc-mc score) "
              "(overrides campaign.record).")
@plant_options
@parallel_options
@user_errors
def endurance(config, hours, flight_s, seed, signature, design, jobs, out, overwrite, resume,
              record, backend, scheduler, quiet, plant, turbulence, dof, airframe):
    """Fly every design fault-free for H flight hours: false resets per flight hour."""
    from pathlib import Path

    from . import api
    from .campaign.endurance import check_hours, endurance_config

    hours = check_hours(hours)
    if flight_s is not None:
        try:
            flight_s = float(flight_s)
        except ValueError:
            raise UserError(f"--flight-s: expected seconds, got {flight_s!r}") from None
    cfg = api.campaign_config(config, seed=seed, signature=signature, plant=plant,
                              turbulence=turbulence, dof=dof, airframe=airframe,
                              design=list(design) or None, record=record)
    cfg = endurance_config(cfg, flight_s)
    if resume and not out:
        raise UserError("--resume: name the run's directory with --out")
    stem = Path(config).with_name(Path(config).stem + "-endurance")
    out_dir = Path(out) if out else _default_out(str(stem), cfg)
    with _interruptible(out_dir):
        res = api.run_endurance(cfg, hours, jobs=jobs, progress=not quiet, backend=backend,
                                scheduler=scheduler, out=out_dir, overwrite=overwrite,
                                resume=resume,
                                command=shlex.join(["ftc-mc", "endurance", config]))
    if res is None:
        click.echo(f"{out_dir}: the endurance run is already complete; nothing to resume")
        return
    click.echo(res.markdown())
    click.echo(f"wrote {out_dir}/: {', '.join(api.ENDURANCE_OUTPUTS)}")


@cli.command()
@click.argument("dirs", nargs=-1, required=True, metavar="DIR...", type=click.Path())
@click.option("-o", "--output", default="report.md", show_default=True,
              type=click.Path(dir_okay=False),
              help="Markdown file to write; figures go to <name>_figures/ beside it.")
@click.option("--allow-mixed", is_flag=True,
              help="Build the report even if the inputs come from different package "
              "versions or git revisions (the report then carries a warning).")
@user_errors
def report(dirs, output, allow_mixed):
    """Write one Markdown report of finished run and scenario directories DIR...

    Reads only their Parquet files, so a report can be rebuilt at any time
    without rerunning anything.
    """
    from . import api

    out = api.build_report(list(dirs), output, allow_mixed=allow_mixed)
    click.echo(f"wrote {out}")


@cli.command()
@click.argument("run_dir", metavar="RUN_DIR", type=click.Path())
@click.option("--detector", required=True, metavar="MODULE:FUNCTION",
              help="Your detector: a NumPy function (signals, names, dt) -> alarm times "
              "[s] per trial (NaN: none), optionally with the block it names "
              "(docs/guides/your-detector.md).")
@click.option("-o", "--out", type=click.Path(),
              help="Folder of the detector's tables [default: RUN_DIR/detectors/<function>/, "
              "which ftc-mc report reads]; inside RUN_DIR only below detectors/.")
@click.option("--name", help="The detector's name in the tables, a plain name (letters, "
              "digits, _ . + -), never a path [default: its function name].")
@user_errors
def score(run_dir, detector, out, name):
    """Score your own detector on RUN_DIR's recorded signals (ftc-mc run or endurance
    --record signals) by the built-in designs' definitions: Tables 2-3 and the ALFA
    scores, or false alarms per flight hour.

    The detector is passed what the aircraft sees (measurements, commands,
    excitation, the flown design's innovations, statistics, resets and belief);
    the truth (mode, b0_*, b1_*) only when its `columns` names it, and then its
    rows are marked as reading the truth. A bad input (name, run folder, signals,
    the detector's return) is refused with one line and nothing written.
    """
    from . import api

    res = api.score_detector(run_dir, detector, out=out, name=name)
    if res["summary"]["reads_truth"].any():
        from .campaign.signals import TRUTH_COLUMNS
        truth = [c for c in res["columns"] if c in TRUTH_COLUMNS]
        click.echo(f"reads the truth ({', '.join(truth)}): an oracle, not a detector an "
                   "aircraft could fly")
    if "trials" in res:
        from .campaign.summary import actuator_rows
        acts = actuator_rows(res["summary"])
        if len(acts):
            click.echo(terminal_table(acts))
    else:
        from .report.endurance import endurance_table
        click.echo(endurance_table(res["summary"]))
    click.echo(f"\nwrote {res['out']}/")


@cli.group("config")
def config_group():
    """Read configuration files (reference: docs/reference/config.md)."""


@config_group.command("show")
@click.argument("path", required=False, metavar="[CONFIG]", type=click.Path())
@click.option("--scenario", is_flag=True,
              help="Read CONFIG as a scenario config (ftc-mc scenario), or with no CONFIG "
              "show a scenario config's defaults [default: a CONFIG with a scenario "
              "section is one].")
@user_errors
def config_show(path, scenario):
    """Print the resolved CONFIG as commented YAML: every section and field, its
    value and a one-line description; a value that is not the default says the
    default.  With no CONFIG, the defaults of a campaign config (ftc-mc run,
    sweep).  The output is itself a valid config.
    """
    from .config import Config, ScenarioConfig, load_any, load_scenario
    from .config.render import render_yaml

    if path is None:
        cfg = ScenarioConfig() if scenario else Config()
        what = "the defaults of a " + ("scenario config (ftc-mc scenario)" if scenario
                                        else "campaign config (ftc-mc run, ftc-mc sweep)")
    else:
        cfg = load_scenario(path) if scenario else load_any(path)
        what = f"{path}, " + ("a scenario config (ftc-mc scenario)"
                              if isinstance(cfg, ScenarioConfig)
                              else "a campaign config (ftc-mc run, ftc-mc sweep)")
    click.echo(render_yaml(cfg, f"ftc-mc config show: {what}"))


def main():
    """Console-script entry point (SIGTERM exits cleanly, releasing locks)."""
    import signal

    def _term(signum, frame):
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, _term)
    cli(prog_name="ftc-mc")
