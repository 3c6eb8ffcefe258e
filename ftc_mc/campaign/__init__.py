"""Monte Carlo campaigns: trials in chunks, in parallel, classified and summarised.

* :mod:`~ftc_mc.campaign.transitions`: the fault transitions of Tables 2-3
  and their draws;
* :mod:`~ftc_mc.campaign.chunk`: the one chunk executor shared by run, sweep
  and endurance (inputs -> kernels -> classified rows);
* :mod:`~ftc_mc.campaign.parallel`: workers (threads, loky processes or a Dask
  cluster), the responsive parent and the progress bar;
* :mod:`~ftc_mc.campaign.runner`: a campaign (``ftc-mc run``);
  :mod:`~ftc_mc.campaign.sweep`: a threshold sweep;
  :mod:`~ftc_mc.campaign.endurance`: fault-free flight hours per design;
* :mod:`~ftc_mc.campaign.summary`: Tables 2-3;
  :mod:`~ftc_mc.campaign.survival`: survival after an elevon lock by lock
  offset, and on the 6-DOF plant inside and outside the trimmable set;
  :mod:`~ftc_mc.campaign.side`: which actuator the 6-DOF side monitor named;
  :mod:`~ftc_mc.campaign.scoring`: the metrics of real-flight studies (ALFA,
  FDDBenchmark);
* :mod:`~ftc_mc.campaign.assemble`: the result tables streamed from the
  chunk store.

The journey of one trial, from a YAML file to a Parquet row
-----------------------------------------------------------

``ftc-mc run configs/elevon_lock.yaml``, trial 17 of the elevon lock:

1. **Command line.** ``cli.run`` parses the options and calls
   ``api.campaign_config``, which reads the YAML (``config.load.read_yaml``)
   and validates it (``config.schema.Config``; a bad field is one line and
   exit 2, and the airframe is loaded and trimmed here so nothing is written
   for an airframe that cannot fly).
2. **API.** ``api.run_campaign`` takes the folder's lock
   (``io.lock.acquire``), prepares it (``io.results.prepare_output_dir``),
   opens the chunk store (``io.chunks.ChunkStore``) and calls
   ``campaign.runner.run_campaign``.
3. **Setup, once, in the parent.** ``campaign.chunk.chunk_spec`` calls
   ``sim.setup.build_setup``: ``model.source.load_plant`` (preset -> trim ->
   linearise -> zero-order hold), ``sim.estimator`` (filter model, Table 1 per
   variant, mode boxes, P0), ``design.lqr``,
   ``cache.engine_tables.cached_engine_tables``,
   ``design.terminal.terminal_costs``, ``sim.truth.truth_plant``.  The result
   is a ``ChunkSpec`` of small picklable arrays.
   ``campaign.runner.plan_chunks`` cuts the trial ids into chunks;
   ``campaign.chunk.warm_up`` compiles the trial kernel once for each compile
   path the designs take (``sim.paths.path_of``), holding a lock beside
   Numba's cache meanwhile (``sim.compiling.compiled_once``) so that another
   process starting at the same time waits and loads it.  On two cores or
   more a compile helper process compiles about half of the path's stages
   into the cache meanwhile (``sim.compile_helper``).  A path not in the cache
   yet is announced on stderr, and then how long its compile took.
4. **Workers.** ``campaign.parallel.run_chunks`` lists the chunk store once
   and sends each chunk not yet in it to a worker (a daemon thread by
   default, the kernels being ``nogil``; a loky process; or a Dask worker)
   running ``campaign.chunk.run_chunk``.  The main thread keeps at most two
   chunks per worker in flight and waits with a 0.2 s timeout; one writer
   thread stores each finished chunk, in whatever order they finish; so a
   signal is handled at once (``interrupt.py``: finished chunks stay, the
   ones in flight are dropped, exit 130 or 143).  In the worker:

   - ``campaign.chunk.trial_inputs``: ``sim.inputs.draw_lanes`` draws each
     trial from its own stream ``np.random.default_rng([17, seed])`` (fault
     draw, process noise, measurement noise, then gusts);
     ``campaign.transitions.Transition.schedule`` turns the draw into a
     two-entry schedule (nominal, then the left elevon locked at the fault
     time); ``sim.inputs.build_inputs`` lays every trial out as one lane of a
     ``TrialInputs``;
   - ``sim.lanes.simulate`` -> ``run_alone`` -> ``run_trials`` calls
     ``core.longitudinal.trial.advance`` once for all the steps, its first
     argument the compile path, with the ``Scheme`` (filter, detection,
     belief, controllers, excitation, selection, engine tables) of each
     design and the ``Flight`` (timing, validity, truth plant); every 0.1 s
     step runs the stages listed in :mod:`ftc_mc.core.longitudinal`, and the
     results land in a ``TrialRecord``;
   - ``campaign.chunk.classify`` turns the record into columns (correct,
     inappropriate, no reset, delays, false resets, status, the elevon the
     belief names), ``cost_columns`` adds the tracking error and control
     energy, and ``first_resets`` keeps the first N resets of each trial when
     ``campaign.reset_log`` asks for it.
5. **Tables and files.** ``campaign.assemble.write_run_tables`` streams
   ``trials.parquet`` (trial 17's row) and ``resets.parquet`` from the chunk
   store through ``io.stream.ParquetStream``: transition by transition,
   design by design, each chunk in chunk order, the order
   ``campaign.runner.sort_rows`` gives in memory whatever order the chunks
   finished in.  Meanwhile ``campaign.summary.summary_row`` turns the columns
   of one (transition, design) at a time into its row of Tables 2-3 (Wilson
   intervals, exact quantiles).  ``api.run_campaign`` writes
   ``summary.parquet`` and ``summary.md`` and removes the chunk store.
   Without a folder (the Python API's ``out=None``) the chunks stay in memory
   and ``campaign.summary.summarize`` builds the same table.
6. **Report.** ``ftc-mc report`` reads only those Parquet files (of
   ``trials.parquet`` only the columns it uses), checks provenance and writes
   the sections of ``report/runs.py`` and the figures of
   ``plots/campaign.py``.

A **sweep** takes the same path with threshold points in its ``ChunkSpec``,
every design at every point; ``sim.lanes.simulate`` shares each trial's start
up to the fault, and the fault-free flights, once per group of designs that
differ at most in Table 1's signature and thresholds (``Design.key``).  An
**endurance** run sends the sweep's fault-free flights through ``run_chunk``
as chunks named ``endurance``.  A **scenario** (:mod:`ftc_mc.scenario`) builds
its ``SimSetup`` from the scenario config directly, maps its schedule to one
lane (``sim.inputs.scenario_inputs``) and runs the same kernels with every
step's history kept.
"""
