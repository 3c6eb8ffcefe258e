"""The ``ftc-mc`` command line: parse, call, print.

Every command turns a bad input into one line on stderr naming the problem and
exit code 2, without a traceback and without writing anything.
"""

from __future__ import annotations

import functools
import json
import sys

import click

from .errors import UserError


def user_errors(func):
    """Turn :class:`UserError` and ``ValueError`` into one line and exit code 2."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except (UserError, ValueError) as exc:
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
@click.option("--save", type=click.Path(dir_okay=False, writable=True),
              help="Write A, B, C, u0, limits and dt to this .npz file.")
@click.option("--airspeed", default=20.0, show_default=True, type=float,
              help="Trim airspeed [m/s].")
@click.option("--gamma", "gamma_deg", default=-3.0, show_default=True, type=float,
              help="Trim flight-path angle [deg].")
@click.option("--dt", default=0.1, show_default=True, type=float,
              help="Sampling period [s].")
@user_errors
def model(as_json, save, airspeed, gamma_deg, dt):
    """Trim point, named eigenvalues and redundancy check of the linear model."""
    from .io.atomic import atomic_path
    from .model.linear import build_plant
    from .model.summary import format_summary, model_summary, save_npz

    if save is not None and not save.endswith(".npz"):
        raise UserError(f"--save: file name must end in .npz, got {save!r}")
    plant = build_plant(V0=airspeed, gamma0_deg=gamma_deg, dt=dt)
    summary = model_summary(plant)
    if save is not None:
        with atomic_path(save) as tmp, open(tmp, "wb") as f:
            save_npz(plant, f)
    click.echo(json.dumps(summary, indent=2) if as_json else format_summary(summary))


def _default_out(config_path: str, cfg=None):
    """``results/<config stem>``, or the first ``-N`` suffix that holds no run.

    A truth plant other than the paper's (linear, still air) is named in the
    stem, e.g. ``results/paper_tables-nonlinear-moderate``.
    """
    from pathlib import Path

    from .io.lock import holder
    from .io.results import RUN_FILES

    stem = Path(config_path).stem
    if cfg is not None and (cfg.plant.kind, cfg.plant.turbulence) != ("linear", "none"):
        stem += f"-{cfg.plant.kind}" + (f"-{cfg.plant.turbulence}"
                                        if cfg.plant.turbulence != "none" else "")
    base = Path("results") / stem
    cand, n = base, 1
    while cand.exists() and (any((cand / f).exists() for f in RUN_FILES)
                             or (cand / ".chunks").exists() or holder(cand) is not None):
        n += 1
        cand = base.with_name(f"{base.name}-{n}")
    return cand


def plant_options(func):
    """``--plant`` and ``--turbulence`` of ``run``, ``sweep`` and ``scenario``."""
    func = click.option("--turbulence",
                        type=click.Choice(["none", "light", "moderate", "severe"]),
                        help="MIL-F-8785C Dryden gusts on the truth plant (overrides "
                        "plant.turbulence).")(func)
    return click.option("--plant", type=click.Choice(["linear", "nonlinear"]),
                        help="Truth plant: the linear model of eq. (1) or the nonlinear "
                        "X8 (overrides plant.kind; the estimator stays linear).")(func)


def _with_plant(cfg, plant, turbulence):
    """``cfg`` with the ``--plant`` and ``--turbulence`` overrides."""
    from .config import with_overrides

    if plant is None and turbulence is None:
        return cfg
    return with_overrides(cfg, plant={"kind": plant, "turbulence": turbulence})


def parallel_options(func):
    """``--backend``, ``--scheduler`` and ``--quiet`` of ``run`` and ``sweep``."""
    func = click.option("--quiet", is_flag=True, help="No progress bar.")(func)
    func = click.option("--scheduler", help="Dask scheduler address, e.g. "
                        "tcp://10.0.0.5:8786 [default: a local cluster].")(func)
    return click.option("--backend", type=click.Choice(["loky", "dask"]), default="loky",
                        show_default=True,
                        help="Worker processes here (loky) or a Dask cluster.")(func)


def _open_chunks(out_dir, identity_json: str, overwrite: bool, resume: bool):
    """The chunk store of a run or sweep directory, new or resumed."""
    from .io.chunks import ChunkStore

    store = ChunkStore(out_dir, identity_json)
    if overwrite:
        store.remove()
    elif resume and not store.exists():
        raise UserError(f"--resume: {out_dir} holds no interrupted run")
    store.open(resume)
    return store


def _interrupted(store, out_dir):
    """Ctrl-C: say where the finished chunks are and how to continue."""
    click.echo(f"\ninterrupted: finished chunks are kept in {store.folder}; "
               f"continue with --resume --out {out_dir}", err=True)
    sys.exit(130)


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--trials", type=int, help="Trials per transition (overrides the config).")
@click.option("--seed", type=int, help="Root seed (overrides the config).")
@click.option("--jobs", type=int, default=-1, show_default=True,
              help="Worker processes; -1: every core (one for a small run). Results do "
              "not depend on it.")
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>, never reused].")
@click.option("--signature", type=click.Choice(["paper", "swapped", "both"]),
              help="Table 1 variant(s) (overrides the config).")
@click.option("--controller", type=click.Choice(["nominal", "reconfiguring"]),
              help="Controller in the loop (overrides the config).")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted run in --out, skipping its finished chunks.")
@plant_options
@parallel_options
@user_errors
def run(config, trials, seed, jobs, out, signature, controller, overwrite, resume, backend,
        scheduler, quiet, plant, turbulence):
    """Run a Monte Carlo campaign (the paper's Tables 2-3) from CONFIG."""
    from pathlib import Path

    from .campaign.runner import resolve_config, run_campaign
    from .config import with_overrides
    from .io.lock import acquire
    from .io.results import prepare_output_dir, provenance, write_run

    if jobs == 0 or jobs < -1:
        raise UserError(f"--jobs: must be a positive count or -1, got {jobs}")
    cfg = resolve_config(config, trials, seed, signature)
    if controller is not None:
        cfg = with_overrides(cfg, controller={"kind": controller})
    cfg = _with_plant(cfg, plant, turbulence)
    if resume and not out:
        raise UserError("--resume: name the run's directory with --out")
    out_dir = Path(out) if out else _default_out(config, cfg)
    config_json = json.dumps(cfg.model_dump(mode="json"), sort_keys=True)
    with acquire(out_dir, command="ftc-mc run"):
        prepare_output_dir(out_dir, overwrite)
        store = _open_chunks(out_dir, config_json, overwrite, resume)
        try:
            result = run_campaign(cfg, jobs=jobs, progress=not quiet, chunks=store,
                                  backend=backend, scheduler=scheduler)
        except KeyboardInterrupt:
            _interrupted(store, out_dir)
        meta = provenance(cfg.model_dump(mode="json"), cfg.campaign.seed, "run")
        md = "# ftc-mc run summary\n\n" + result.markdown() + "\n"
        write_run(out_dir, result.trials, result.resets, result.summary, md, meta)
        store.remove()
    click.echo(result.markdown())
    click.echo(f"\nwrote {out_dir}/: trials.parquet, resets.parquet, summary.parquet, "
               "summary.md")


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>, never reused].")
@click.option("--seed", type=int, help="Noise seed (overrides the config).")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@plant_options
@user_errors
def scenario(config, out, seed, overwrite, plant, turbulence):
    """Run the closed-loop scenario of CONFIG (the paper's Table 4 by default)."""
    from pathlib import Path

    from .config import load_scenario
    from .io.lock import acquire
    from .io.results import prepare_output_dir, provenance
    from .scenario import run_scenario, summary_markdown, write_scenario

    sc = _with_plant(load_scenario(config), plant, turbulence)
    if seed is not None and seed < 0:
        raise UserError(f"--seed: must be >= 0, got {seed}")
    out_dir = Path(out) if out else _default_out(config, sc)
    with acquire(out_dir, command="ftc-mc scenario"):
        prepare_output_dir(out_dir, overwrite)
        res = run_scenario(sc, seed=seed)
        meta = provenance(res.config.model_dump(mode="json"), res.config.scenario.seed,
                          "scenario")
        files = write_scenario(res, out_dir, meta)
    click.echo(summary_markdown(res))
    click.echo(f"wrote {out_dir}/: " + ", ".join(p.name for p in files))


@cli.command()
@click.argument("config", type=click.Path(dir_okay=True))
@click.option("--thresholds", help="t_q = t_nx values: start:stop:step or a,b,c.")
@click.option("--tq", help="t_q values (a grid with --tnx).")
@click.option("--tnx", help="t_nx values (a grid with --tq).")
@click.option("--transitions", help="Comma list of transitions (overrides the config).")
@click.option("--signature", type=click.Choice(["paper", "swapped", "both"]),
              help="Table 1 variant(s) (overrides the config).")
@click.option("--trials", type=int, help="Trials per transition (overrides the config).")
@click.option("--flights", type=int, help="Fault-free flights per point [default: trials].")
@click.option("--jobs", type=int, default=-1, show_default=True,
              help="Worker processes; -1: every core. Results do not depend on it.")
@click.option("--out", type=click.Path(file_okay=False),
              help="Output directory [default: results/<config name>, never reused].")
@click.option("--overwrite", is_flag=True, help="Replace results already in --out.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted sweep in --out, skipping its finished chunks.")
@plant_options
@parallel_options
@user_errors
def sweep(config, thresholds, tq, tnx, transitions, signature, trials, flights, jobs, out,
          overwrite, resume, backend, scheduler, quiet, plant, turbulence):
    """Sweep the Table 1 thresholds: Tables 2-3 and false resets per flight hour."""
    from pathlib import Path

    from .campaign.runner import resolve_config
    from .campaign.sweep import run_sweep, sweep_markdown, threshold_points
    from .io.atomic import write_text
    from .config import with_overrides
    from .io.lock import acquire
    from .io.results import prepare_output_dir, provenance, write_parquet

    cfg = resolve_config(config, trials, None, signature)
    if transitions is not None:
        names = [t.strip() for t in transitions.split(",") if t.strip()]
        cfg = with_overrides(cfg, campaign={"transitions": names})
    cfg = _with_plant(cfg, plant, turbulence)
    points = threshold_points(thresholds, tq, tnx)
    if flights is not None and flights < 1:
        raise UserError(f"--flights: must be >= 1, got {flights}")
    if jobs == 0 or jobs < -1:
        raise UserError(f"--jobs: must be a positive count or -1, got {jobs}")
    if resume and not out:
        raise UserError("--resume: name the sweep's directory with --out")
    out_dir = Path(out) if out else _default_out(config, cfg)
    identity = {"config": cfg.model_dump(mode="json"), "points": [list(p) for p in points],
                "flights": flights}
    with acquire(out_dir, command="ftc-mc sweep"):
        prepare_output_dir(out_dir, overwrite)
        store = _open_chunks(out_dir, json.dumps(identity, sort_keys=True), overwrite,
                             resume)
        try:
            res = run_sweep(cfg, points, flights=flights, jobs=jobs, progress=not quiet,
                            backend=backend, scheduler=scheduler, chunks=store)
        except KeyboardInterrupt:
            _interrupted(store, out_dir)
        meta = provenance(cfg.model_dump(mode="json"), cfg.campaign.seed, "sweep")
        meta["points"] = [list(p) for p in points]
        meta["trial_steps"] = {"simulated": res.simulated_steps, "alone": res.alone_steps}
        write_parquet(res.table, out_dir / "sweep.parquet", meta)
        md = sweep_markdown(res)
        write_text(out_dir / "sweep.md", md)
        store.remove()
    click.echo(md)
    click.echo(f"wrote {out_dir}/: sweep.parquet, sweep.md")


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
    from pathlib import Path

    from .report import build_report

    out = build_report([Path(d) for d in dirs], Path(output), allow_mixed=allow_mixed)
    click.echo(f"wrote {out}")


def main():
    """Console-script entry point (SIGTERM exits cleanly, releasing locks)."""
    import signal

    def _term(signum, frame):
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, _term)
    cli(prog_name="ftc-mc")
