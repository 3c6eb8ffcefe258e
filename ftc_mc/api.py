"""The Python API: one function per command, each returning DataFrames.

::

    import ftc_mc
    cfg = ftc_mc.load_config("configs/paper_tables.yaml")      # validated Config
    res = ftc_mc.run_campaign(cfg, trials=200, jobs=2)         # res.summary, res.trials
    sw = ftc_mc.run_sweep(cfg, "10,25,50", trials=100)         # sw.table
    en = ftc_mc.run_endurance(cfg, hours=10, jobs=2)           # en.summary, en.resets
    sc = ftc_mc.run_scenario("configs/paper_scenario.yaml")    # sc.timeseries, sc.events
    ftc_mc.build_report(["results/paper_tables"], "report.md")

Every function takes a config object, a mapping or a YAML path.  Without
``out`` nothing is written; with ``out`` the results go to that directory
exactly as the command line writes them: under the directory's lock, in chunks
that ``resume=True`` continues after a crash, each file atomic and carrying its
provenance.  The command line (:mod:`ftc_mc.cli`) is a thin layer over these.

Bad input raises :class:`~ftc_mc.errors.UserError` (a ``ValueError``) with a
one-line message; nothing is written then.
"""

from __future__ import annotations

import json
import shlex
import sys
from pathlib import Path

from .errors import UserError

RUN_OUTPUTS = ("summary.parquet", "trials.parquet", "resets.parquet", "summary.md")
"""Files of a finished ``run`` directory (the first holds the metadata checked)."""
SWEEP_OUTPUTS = ("sweep.parquet", "sweep.md")
"""Files of a finished ``sweep`` directory."""
ENDURANCE_OUTPUTS = ("endurance.parquet", "flights.parquet", "false_resets.parquet",
                     "endurance.md")
"""Files of a finished ``endurance`` directory (the first holds the metadata checked)."""
SCENARIO_OUTPUTS = ("timeseries.parquet", "events.parquet", "segments.parquet",
                    "summary.md")
"""Files of a ``scenario`` directory besides its figures."""


# -- configs ----------------------------------------------------------------------

def load_config(path):
    """Read and validate a config file: a campaign (or sweep) or a scenario.

    Parameters
    ----------
    path : str, Path, dict, Config or ScenarioConfig
        A YAML file, or its parsed mapping; a file with a top-level
        ``scenario`` section is a scenario.  A config object is returned as is.

    Returns
    -------
    Config or ScenarioConfig

    Raises
    ------
    UserError
        Missing or unreadable file, malformed YAML, or an invalid field (the
        message names it).
    """
    from .config import Config, ScenarioConfig
    from .config.load import read_yaml, validate_model

    if isinstance(path, (Config, ScenarioConfig)):
        return path
    data, source = (path, "config") if isinstance(path, dict) else (read_yaml(path),
                                                                    str(path))
    if isinstance(data, dict) and "scenario" in data:
        return validate_model(ScenarioConfig, data, source)
    return validate_model(Config, data, source)


def _listed(names):
    if isinstance(names, str):
        return [t.strip() for t in names.split(",") if t.strip()]
    return None if names is None else list(names)


def _design_names(cfg, design) -> list | None:
    """The names of ``--design`` (a string is a comma list), checked against the
    built-in designs and the config's ``designs`` section."""
    from .config.schema import BUILTIN_DESIGNS

    names = _listed(design)
    if not names:
        return None
    known = [*BUILTIN_DESIGNS, *cfg.designs]
    for n in names:
        if n not in known:
            raise UserError(f"--design: unknown design {n!r}; known designs: "
                            f"{', '.join(known)}")
    if len(set(names)) != len(names):
        raise UserError(f"--design: a design is named twice in {names}")
    return names


def _design_override(cfg, design, signature) -> dict | None:
    """``campaign`` fields that run the designs ``design`` (built-in ones first),
    replacing ``campaign.signature`` and ``campaign.designs``."""
    from .config.schema import BUILTIN_DESIGNS

    names = _design_names(cfg, design)
    if names is None:
        return None
    if signature is not None:
        raise UserError("--design: give either --design or --signature, not both")
    builtin = [n for n in BUILTIN_DESIGNS if n in names]
    sig = "both" if len(builtin) == 2 else builtin[0] if builtin else "none"
    return {"signature": sig, "designs": [n for n in names if n not in BUILTIN_DESIGNS]}


def campaign_config(config, *, trials=None, seed=None, signature=None, transitions=None,
                    controller=None, plant=None, turbulence=None, dof=None, airframe=None,
                    design=None, reset_log=None, record=None):
    """A validated campaign :class:`~ftc_mc.config.Config` with overrides.

    Parameters
    ----------
    config : str, Path, dict or Config
    trials, seed : int, optional
        ``campaign.trials``, ``campaign.seed``.
    signature : {"paper", "swapped", "both", "none"}, optional
    transitions : list of str or str, optional
        Transition names (a string is a comma list).
    controller : {"nominal", "reconfiguring"}, optional
    plant : {"linear", "nonlinear"}, optional
    turbulence : {"none", "light", "moderate", "severe"}, optional
    dof : {3, 6}, optional
        ``plant.dof``: the longitudinal truth or the 6-DOF flying wing.
    airframe : str or Path, optional
        ``model.airframe``: a preset name, an airframe YAML file or a linear
        model (``.npz``/``.mat``).
    design : list of str or str, optional
        The designs to run (``--design``): ``paper``, ``swapped`` or keys of the
        ``designs`` section, on the same trials; replaces ``campaign.signature``
        and ``campaign.designs`` (the built-in designs run first).
    reset_log : str, optional
        ``campaign.reset_log``: ``all``, ``none`` or ``first-N``.
    record : {"none", "signals"}, optional
        ``campaign.record``: write every step's signals to ``signals/``
        (``docs/reference/outputs.md``).
    """
    from .config import Config, ScenarioConfig, load_config as load_campaign
    from .config import parse_config, with_overrides

    if isinstance(config, ScenarioConfig):
        raise UserError("config: a scenario config; run it with run_scenario "
                        "(ftc-mc scenario)")
    if isinstance(config, Config):
        cfg = config
    elif isinstance(config, dict):
        cfg = parse_config(config)
    else:
        cfg = load_campaign(config)
    over = {"campaign": {"trials": trials, "seed": seed, "signature": signature,
                         "transitions": _listed(transitions), "reset_log": reset_log,
                         "record": record},
            "controller": {"kind": controller},
            "plant": {"kind": plant, "turbulence": turbulence, "dof": dof},
            "model": {"airframe": None if airframe is None else str(airframe)}}
    over = {k: v for k, v in over.items() if any(x is not None for x in v.values())}
    cfg = with_overrides(cfg, **over) if over else cfg
    runs = _design_override(cfg, design, signature)
    return cfg if runs is None else with_overrides(cfg, campaign=runs)


def scenario_config(config, *, plant=None, turbulence=None, dof=None, airframe=None,
                    design=None):
    """A validated :class:`~ftc_mc.config.ScenarioConfig` with plant overrides.

    Parameters
    ----------
    config : str, Path, dict or ScenarioConfig
    plant, turbulence, dof, airframe : optional
        As in :func:`campaign_config`.
    design : str, optional
        The one design to fly (``--design``): ``paper``, ``swapped`` (then
        ``scenario.signature``) or a key of the ``designs`` section
        (``scenario.design``).
    """
    from .config import Config, ScenarioConfig, load_scenario, with_overrides
    from .config.schema import BUILTIN_DESIGNS
    from .config.load import validate_model

    if isinstance(config, Config):
        raise UserError("config: a campaign config; a scenario needs a scenario config "
                        "(see configs/paper_scenario.yaml)")
    if isinstance(config, ScenarioConfig):
        sc = config
    elif isinstance(config, dict):
        sc = validate_model(ScenarioConfig, config, "config")
    else:
        sc = load_scenario(config)
    over = {"plant": {"kind": plant, "turbulence": turbulence, "dof": dof},
            "model": {"airframe": None if airframe is None else str(airframe)}}
    over = {k: v for k, v in over.items() if any(x is not None for x in v.values())}
    sc = with_overrides(sc, **over) if over else sc
    names = _design_names(sc, design)
    if names is None:
        return sc
    if len(names) != 1:
        raise UserError(f"--design: a scenario flies one design, got {len(names)}: "
                        f"{', '.join(names)}")
    data = sc.model_dump()
    builtin = names[0] in BUILTIN_DESIGNS
    data["scenario"].update(design=None if builtin else names[0],
                            signature=names[0] if builtin else data["scenario"]["signature"])
    return validate_model(ScenarioConfig, data, "options")


# -- output directories -----------------------------------------------------------

def _who(name: str) -> str:
    """The command written to the lock file of an API call."""
    return f"ftc_mc.{name}() in {shlex.join(sys.argv) or 'python'}"


def _check_jobs(jobs) -> None:
    if jobs == 0 or jobs < -1:
        raise UserError(f"--jobs: must be a positive count or -1, got {jobs}")


def _check_out(out, resume: bool) -> Path | None:
    if out is None:
        if resume:
            raise UserError("--resume: name the directory to continue with --out")
        return None
    return Path(out)


def _current_identity(identity):
    """A result folder's recorded identity with its configuration as the current
    schema resolves it (:func:`ftc_mc.config.load.as_current`): a run's identity
    is its configuration, a sweep's or an endurance run's a mapping holding one."""
    from .config.load import as_current
    from .config.schema import Config

    if isinstance(identity, dict) and isinstance(identity.get("config"), dict):
        return {**identity, "config": as_current(Config, identity["config"])}
    return as_current(Config, identity)


def _open_chunks(out_dir: Path, identity_json: str, overwrite: bool, resume: bool):
    """The chunk store of a run or sweep directory, new or resumed."""
    from .io.chunks import ChunkStore

    store = ChunkStore(out_dir, identity_json)
    if overwrite:
        store.remove()
        import shutil
        shutil.rmtree(out_dir / "signals", ignore_errors=True)  # an older run's recording
    elif resume and not store.exists():
        raise UserError(f"--resume: {out_dir} holds no interrupted run")
    store.open(resume, resolve=_current_identity)
    return store


def _prepare(out_dir: Path, overwrite: bool, resume: bool) -> None:
    """Refuse an output folder that holds results (``io.results.prepare_output_dir``),
    except when resuming a run whose chunks are still there: a run interrupted
    while it wrote its result files (the last minutes of a big run) may have
    written some of them, and resuming writes them again."""
    from .io.chunks import ChunkStore
    from .io.results import prepare_output_dir

    if not (resume and not overwrite and ChunkStore(out_dir, "").exists()):
        prepare_output_dir(out_dir, overwrite)


def _finished(out_dir: Path, kind: str, files, identity: dict) -> bool:
    """Whether ``out_dir`` holds a finished ``kind`` with this identity.

    Raises
    ------
    UserError
        It holds a finished ``kind`` of another configuration.
    """
    from .io.chunks import ChunkStore
    from .io.results import read_metadata

    if not all((out_dir / f).is_file() for f in files):
        return False
    try:
        meta = read_metadata(out_dir / files[0])
    except Exception:  # noqa: BLE001 -- unreadable: not ours to judge here
        return False
    if meta.get("kind") != kind:
        return False
    recorded = _current_identity({k: meta.get(k) for k in identity})
    if any(recorded[k] != v for k, v in identity.items()):
        raise UserError(f"--resume: {out_dir} holds a finished {kind} of another "
                        "configuration (or other options)")
    ChunkStore(out_dir, "").remove()  # left if the process died just after the last file
    return True


# -- the commands -----------------------------------------------------------------

def run_campaign(config, *, trials=None, seed=None, signature=None, controller=None,
                 plant=None, turbulence=None, dof=None, airframe=None, design=None,
                 reset_log=None, record=None,
                 jobs: int = 1,
                 progress: bool = True,
                 backend: str = "threads", scheduler: str | None = None, out=None,
                 overwrite: bool = False, resume: bool = False,
                 command: str | None = None):
    """Run a Monte Carlo campaign: the paper's Tables 2-3 (``ftc-mc run``).

    Parameters
    ----------
    config : str, Path, dict or Config
        YAML path, parsed mapping or validated configuration.
    trials, seed, signature, controller, plant, turbulence, airframe, design, reset_log, record : optional
        Overrides of the config (:func:`campaign_config`); ``record="signals"``
        writes every step of every trial to ``out/signals/``.
    jobs : int
        Workers (``backend``); 1 runs here alone, -1 uses every core (or, on
        worker processes, this process alone for a small run).  The results do
        not depend on it.
    progress : bool
        Show a progress bar.
    backend : {"threads", "loky", "dask"}
    scheduler : str, optional
        Dask scheduler address (``backend="dask"``); a local cluster if None.
    out : str or Path, optional
        Write ``trials.parquet``, ``resets.parquet``, ``summary.parquet`` and
        ``summary.md`` there (as ``ftc-mc run --out``).  Nothing is written
        without it.
    overwrite : bool
        Replace results already in ``out``.
    resume : bool
        Continue the interrupted run in ``out``, skipping its finished chunks.
    command : str, optional
        Named to another process that finds ``out`` locked.

    Returns
    -------
    CampaignResult or None
        ``.summary`` (one row per transition and variant), ``.trials`` (one
        row per trial and variant), ``.resets`` (one row per reset) and
        ``.config``; with ``out``, ``.trials`` and ``.resets`` are read from
        the files written there when asked for (a run of millions of trials
        never holds them in memory).  None if ``resume`` found the run already
        finished in ``out`` (nothing was run).

    Raises
    ------
    UserError
        A bad config or option, or an ``out`` that is busy, holds other results
        or (with ``resume``) no interrupted run; nothing is written then.
    KeyboardInterrupt
        Ctrl-C (or :class:`ftc_mc.interrupt.Interrupted` for SIGINT/SIGTERM
        under :func:`ftc_mc.interrupt.stop_on_signals`): the finished chunks
        stay in ``out``; ``resume=True`` continues.
    """
    from .campaign.runner import run_campaign as run
    from .io.lock import acquire
    from .io.results import provenance, write_summary

    _check_jobs(jobs)
    cfg = campaign_config(config, trials=trials, seed=seed, signature=signature,
                          controller=controller, plant=plant, turbulence=turbulence, dof=dof,
                          airframe=airframe, design=design, reset_log=reset_log,
                          record=record)
    kw = dict(jobs=jobs, progress=progress, backend=backend, scheduler=scheduler)
    out_dir = _check_out(out, resume)
    if out_dir is None:
        return run(cfg, **kw)
    config_json = cfg.model_dump(mode="json")
    with acquire(out_dir, command=command or _who("run_campaign")):
        if resume and not overwrite and _finished(out_dir, "run", RUN_OUTPUTS,
                                                  {"config": config_json}):
            return None
        _prepare(out_dir, overwrite, resume)
        store = _open_chunks(out_dir, json.dumps(config_json, sort_keys=True), overwrite,
                             resume)
        meta = provenance(config_json, cfg.campaign.seed, "run")
        try:
            result = run(cfg, chunks=store, out=out_dir, meta=meta, **kw)
        except Exception:  # e.g. draws outside the command range, no Dask scheduler
            store.discard_if_empty()
            raise
        md = "# ftc-mc run summary\n\n" + result.markdown() + "\n"
        sets = result.trimmable_sets()  # the split summary.md shows, for the report
        write_summary(out_dir, result.summary, md,
                      {**meta, "trimmable_sets": {n: list(v) for n, v in sets.items()}}
                      if sets else meta)
        store.remove()
    return result


def _spec(values, option: str):
    """A threshold spec for :func:`~ftc_mc.campaign.sweep.parse_spec` from a string,
    a number or a sequence of numbers."""
    if values is None or isinstance(values, str):
        return values
    if isinstance(values, (int, float)):
        values = [values]
    try:
        return ",".join(repr(float(v)) for v in values)
    except (TypeError, ValueError):
        raise UserError(f"{option}: expected numbers, got {values!r}") from None


def run_sweep(config, thresholds=None, *, tq=None, tnx=None, transitions=None,
              signature=None, trials=None, seed=None, flights: int | None = None,
              plant=None, turbulence=None, dof=None, airframe=None, design=None, jobs: int = 1,
              progress: bool = True, backend: str = "threads", scheduler: str | None = None,
              out=None, overwrite: bool = False, resume: bool = False,
              command: str | None = None):
    """Sweep the Table 1 thresholds (``ftc-mc sweep``).

    Parameters
    ----------
    config : str, Path, dict or Config
    thresholds : str or sequence of float, optional
        ``t_q = t_nx`` values: ``"start:stop:step"``, ``"a,b,c"`` or numbers.
    tq, tnx : str or sequence of float, optional
        A grid of ``t_q`` by ``t_nx`` values instead of ``thresholds``.
    transitions, signature, trials, seed, plant, turbulence, airframe, design : optional
        Overrides of the config (:func:`campaign_config`); every design runs at
        every threshold point.
    flights : int, optional
        Fault-free flights per point for the false-reset rate (default: trials).
    jobs, progress, backend, scheduler, out, overwrite, resume, command
        As in :func:`run_campaign`; ``out`` receives ``sweep.parquet`` and
        ``sweep.md``.

    Returns
    -------
    SweepResult or None
        ``.table`` (one row per threshold point, transition and variant, with
        the false resets per flight hour), ``.trials`` (None with ``out``: the
        table is assembled from the chunks one point at a time), ``.points``,
        ``.saving``.  None if ``resume`` found the sweep already finished.
    """
    from .campaign.sweep import run_sweep as sweep, sweep_markdown, threshold_points
    from .io.atomic import write_text
    from .io.lock import acquire
    from .io.results import provenance, write_parquet

    cfg = campaign_config(config, trials=trials, seed=seed, signature=signature,
                          transitions=transitions, plant=plant, turbulence=turbulence, dof=dof,
                          airframe=airframe, design=design)
    if cfg.campaign.record != "none":
        raise UserError("campaign.record: a sweep does not record signals; record a run "
                        "(ftc-mc run --record signals) and score thresholds offline on it")
    points = threshold_points(_spec(thresholds, "--thresholds"), _spec(tq, "--tq"),
                              _spec(tnx, "--tnx"))
    if flights is not None and flights < 1:
        raise UserError(f"--flights: must be >= 1, got {flights}")
    _check_jobs(jobs)
    kw = dict(flights=flights, jobs=jobs, progress=progress, backend=backend,
              scheduler=scheduler)
    out_dir = _check_out(out, resume)
    if out_dir is None:
        return sweep(cfg, points, **kw)
    config_json = cfg.model_dump(mode="json")
    point_list = [list(p) for p in points]
    identity = {"config": config_json, "points": point_list, "flights": flights}
    with acquire(out_dir, command=command or _who("run_sweep")):
        if resume and not overwrite and _finished(
                out_dir, "sweep", SWEEP_OUTPUTS, {"config": config_json,
                                                   "points": point_list}):
            return None
        _prepare(out_dir, overwrite, resume)
        store = _open_chunks(out_dir, json.dumps(identity, sort_keys=True), overwrite,
                             resume)
        try:
            res = sweep(cfg, points, chunks=store, **kw)
        except Exception:
            store.discard_if_empty()
            raise
        meta = provenance(config_json, cfg.campaign.seed, "sweep")
        meta["points"] = point_list
        meta["trial_steps"] = {"simulated": res.simulated_steps, "alone": res.alone_steps}
        write_parquet(res.table, out_dir / "sweep.parquet", meta)
        write_text(out_dir / "sweep.md", sweep_markdown(res))
        store.remove()
    return res


def run_endurance(config, hours, *, flight_s: float | None = None, seed=None,
                  signature=None, plant=None, turbulence=None, dof=None, airframe=None,
                  design=None, record=None,
                  jobs: int = 1, progress: bool = True, backend: str = "threads",
                  scheduler: str | None = None, out=None, overwrite: bool = False,
                  resume: bool = False, command: str | None = None):
    """Fault-free flight hours per design: false resets per hour (``ftc-mc endurance``).

    Parameters
    ----------
    config : str, Path, dict or Config
    hours : float
        Flight hours to fly (finite, > 0); rounded up to whole flights.
    flight_s : float, optional
        Length of each flight [s] (default ``timing.duration_s``); it must be
        longer than the filters' start-up
        (:func:`ftc_mc.campaign.endurance.startup_s`).
    seed, signature, plant, turbulence, airframe, design, record : optional
        Overrides of the config (:func:`campaign_config`); every design flies
        the same flights; ``record="signals"`` writes every step of every
        flight to ``out/signals/`` (false alarms of a user's detector).
    jobs, progress, backend, scheduler, out, overwrite, resume, command
        As in :func:`run_campaign`; ``out`` receives ``endurance.parquet`` (one
        row per design), ``flights.parquet``, ``false_resets.parquet`` and
        ``endurance.md``.

    Returns
    -------
    EnduranceResult or None
        ``.summary``, ``.flights``, ``.resets``; None if ``resume`` found the
        run already finished in ``out``.
    """
    from .campaign.endurance import (check_hours, endurance_config, endurance_spec,
                                     run_endurance as endure)
    from .io.atomic import write_text
    from .io.lock import acquire
    from .io.results import prepare_output_dir, provenance, write_parquet

    cfg = campaign_config(config, seed=seed, signature=signature, plant=plant,
                          turbulence=turbulence, dof=dof, airframe=airframe, design=design,
                          record=record)
    hours = check_hours(hours)
    cfg = endurance_config(cfg, flight_s)
    _check_jobs(jobs)
    spec = endurance_spec(cfg)  # a flight shorter than the start-up: refused here
    kw = dict(jobs=jobs, progress=progress, backend=backend, scheduler=scheduler, spec=spec)
    out_dir = _check_out(out, resume)
    if out_dir is None:
        return endure(cfg, hours, **kw)
    config_json = cfg.model_dump(mode="json")
    identity = {"config": config_json, "hours": hours}
    with acquire(out_dir, command=command or _who("run_endurance")):
        if resume and not overwrite and _finished(out_dir, "endurance", ENDURANCE_OUTPUTS,
                                                  identity):
            return None
        prepare_output_dir(out_dir, overwrite)
        store = _open_chunks(out_dir, json.dumps(identity, sort_keys=True), overwrite,
                             resume)
        try:
            res = endure(cfg, hours, chunks=store, **kw)
        except Exception:
            store.discard_if_empty()
            raise
        meta = provenance(config_json, cfg.campaign.seed, "endurance")
        meta["hours"] = hours
        write_parquet(res.flights, out_dir / "flights.parquet", meta)
        write_parquet(res.resets, out_dir / "false_resets.parquet", meta)
        write_parquet(res.summary, out_dir / "endurance.parquet", meta)
        write_text(out_dir / "endurance.md", "# ftc-mc endurance\n\n" + res.markdown() + "\n")
        store.remove()
    return res


def run_scenario(config, *, seed: int | None = None, plant=None, turbulence=None, dof=None,
                 airframe=None, design=None, out=None, overwrite: bool = False,
                 command: str | None = None):
    """Fly one closed-loop scenario: the paper's Table 4 by default (``ftc-mc scenario``).

    Parameters
    ----------
    config : str, Path, dict or ScenarioConfig
    seed : int, optional
        Noise seed (overrides ``scenario.seed``).
    plant, turbulence, airframe : str, optional
        Overrides, as in :func:`campaign_config`.
    design : str, optional
        The design flown (:func:`scenario_config`).
    out : str or Path, optional
        Write ``timeseries.parquet``, ``events.parquet``, ``segments.parquet``,
        Figs. 6-12 and ``summary.md`` there.
    overwrite, command
        As in :func:`run_campaign`.

    Returns
    -------
    ScenarioResult
        ``.timeseries`` (one row per 0.1 s step), ``.events``, ``.segments``
        (one row per schedule entry), ``.status`` and ``.config``.
    """
    from .io.lock import acquire
    from .io.results import prepare_output_dir, provenance
    from .scenario import run_scenario as run, write_scenario

    sc = scenario_config(config, plant=plant, turbulence=turbulence, dof=dof, airframe=airframe,
                         design=design)
    if seed is not None and seed < 0:
        raise UserError(f"--seed: must be >= 0, got {seed}")
    out_dir = _check_out(out, False)
    if out_dir is None:
        return run(sc, seed=seed)
    with acquire(out_dir, command=command or _who("run_scenario")):
        prepare_output_dir(out_dir, overwrite)
        res = run(sc, seed=seed)
        meta = provenance(res.config.model_dump(mode="json"), res.config.scenario.seed,
                          "scenario")
        write_scenario(res, out_dir, meta)
    return res


def build_report(dirs, out="report.md", *, allow_mixed: bool = False) -> Path:
    """Write one Markdown report of finished result directories (``ftc-mc report``).

    Parameters
    ----------
    dirs : str, Path or list of them
        Run, sweep and scenario directories, in any mix; only their Parquet
        files are read.
    out : str or Path
        The Markdown file; figures go to ``<out stem>_figures/`` beside it.
    allow_mixed : bool
        Accept inputs of different package versions or git revisions.

    Returns
    -------
    Path
        ``out``.
    """
    from .report import build_report as build

    if isinstance(dirs, (str, Path)):
        dirs = [dirs]
    return build([Path(d) for d in dirs], Path(out), allow_mixed=allow_mixed)


def score_detector(run_dir, detector, *, out=None, name=None):
    """Score a detector of your own on a run's recorded signals (``ftc-mc score``).

    Parameters
    ----------
    run_dir : str or Path
        A directory of ``ftc-mc run --record signals`` (Tables 2-3 and the ALFA
        scores, beside the built-in designs) or ``ftc-mc endurance --record
        signals`` (false alarms per flight hour).
    detector : callable or str
        ``detector(signals, names, dt)`` returning per trial the first alarm
        time [s] (NaN: none), optionally with the block or actuator it names;
        or ``"module:function"`` (:mod:`ftc_mc.campaign.detector`).
    out : str or Path, optional
        Folder of the detector's tables (default ``run_dir/detectors/<name>/``,
        which ``ftc-mc report`` reads).
    name : str, optional
        The detector's name in the tables (default its function name): a plain
        name, never a path.

    Returns
    -------
    dict
        ``summary``, ``trials`` (or ``flights``), ``columns`` (the signal
        columns the detector was passed: the observable ones, or those its
        ``columns`` attribute names) and ``out``.

    Raises
    ------
    UserError
        A bad name or output folder, a module that cannot be imported, a run
        folder, table, metadata or signals file that is missing, damaged or
        inconsistent, a run recorded without signals, a detector that raises
        or returns anything but one valid alarm time (and block) per trial;
        nothing is written then.
    """
    from .campaign.detector import score_detector as score

    return score(run_dir, detector, out=out, name=name)

