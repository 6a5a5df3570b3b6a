"""``gyro-instrument bench``: what accuracy costs, in computer time and in observation time.

Writes CSV files, PNG plots (when matplotlib is installed: the ``plot`` extra; the CSVs never
need it) and a markdown summary (``summary.md``) to ``--out``. Studies:

* ``work_precision.csv`` (:mod:`.work_precision`) — error at the end of the run against a tight reference
  versus CPU time, per fidelity tier and setting:

  - the Foucault pendulum (67 m, 2°, a sidereal day at 20 Hz; 1 h with ``--quick``): Binet's
    closed form (linear model), Quet's comparison pendulum (the first swing turned by its apsidal
    angle), the small-angle model, and the full equations with DOP853 across tolerances (the
    textbook baseline on the Cartesian rotating-frame pendulum) or with the parareal fast path;
  - the directing-plane gyroscope (quet_paris, 1 h): Quet's closed form (eq. 9 with the exact
    swing), his reduced equations and the exact hinge-chain equations across tolerances;
* ``targets.csv`` — the speed targets measured in one run (fast path: CPU, end error and the
  DOP853/fast-path CPU ratio at the same error; one hour of both plane-gyroscope configurations;
  estimator samples per second; the ROS suite at 100 Hz with its recording checked complete);
* ``streaming.csv`` (:mod:`.streaming`) — the whole ``simulate --out X.parquet`` process for a
  sidereal day of foucault_pantheon (1 h with ``--quick``) against a textbook ``solve_ivp`` script
  in the same run (wall clock, end errors against the same reference), peak RSS of 1 h, 24 h and
  48 h runs, CSV and Parquet writer MB/s;
* ``observation_time.csv`` — latitude and Earth-rate rms error versus observation time (1–60 min)
  for the sine fit, Quet's counting and the Cramér–Rao bound, with the mean reported σ and the
  noise-free error, over seeds run in a process pool
  (:func:`gyro_instrument.core.parallel.process_executor`; any ``concurrent.futures``-compatible
  executor, e.g. a Dask client's, can be passed instead);
* ``systematic_floors.csv`` — the noise-free bias of the gyroscope pair (item 9, eq. 10) and of
  the pendulum alone on quet_paris with a 1 h spin decay, with every estimator correction applied
  and with each of finite amplitude, spin decay and the ellipse precession left out;
* ``planner.csv`` — the planner's accuracy: for ``quet_paris`` (1″ of latitude, 1e-10 rad/s of
  Earth rate) the observation time ``gyro-instrument plan`` gives and the rms achieved by seeded
  runs at that time (:func:`.studies.planner_accuracy`);
* ``site_sweep.csv`` — the same errors for the default scene moved over latitudes −85°…85°;
* ``realtime.csv``, ``gimbal_work_precision.csv`` (:mod:`.realtime`) — simulated seconds per CPU
  second of every instrument configuration of every shipped scene (each ``configuration``,
  ``integrator`` and ``model`` choice), goal 10; the gimbal's error versus CPU for the hinge chain
  and the closed form through three DOP853 drivers (free and locked rings);
* ``effect_cost.csv`` (:mod:`.effect_cost`) — for each effect of a scene: CPU with and without
  it, and the error made by leaving it out (angles, noise-free latitude and Earth rate);
* ``--scene SCENE`` (with ``--set``): only the observation-time study (floors with the scene's own
  effects) and the planner's accuracy on that scene (:func:`.studies.run_scene_bench`), with
  targets whose plans land near the scene's ``duration_s``;
* ``marine_checks.csv`` (:mod:`.marine_checks`) — the marine gyrocompass against published figures
  (issue 39 item 4): the NAVIGAT X MK 1 speed-error table against four laws, the emulated compass's
  settle point and its equations at rest; its period, settling and decrement against Slater, Chalmers and
  the NAVIGAT manual;
* ``*.png`` (:mod:`.plots`) — work-precision, observation-time and effect-cost diagrams.
"""
