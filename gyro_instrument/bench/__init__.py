"""``gyro-instrument bench``: what accuracy costs, in computer time and in observation time.

Writes CSV files and a markdown summary (``summary.md``) to ``--out``; PNG plots are a later
addition (matplotlib stays optional: the CSV never needs it). Studies:

* ``work_precision.csv`` — the Foucault pendulum (67 m, 2°): error of the swing-plane azimuth at
  the end of the run against a tight-tolerance reference, versus CPU time, for DOP853 across
  tolerances (the textbook baseline on the Cartesian rotating-frame pendulum) and for the fidelity
  tiers: Binet's analytic ellipse (linear model, closed form) and the full equations;
* ``targets.csv`` — the issue's speed targets measured in one run: one hour of both
  plane-gyroscope configurations, estimator samples per second;
* ``observation_time.csv`` — latitude rms error versus observation time for the sine fit, Quet's
  counting and the Cramér–Rao bound, over seeds run in a process pool
  (:func:`gyro_instrument.core.parallel.process_executor`; any ``concurrent.futures``-compatible
  executor, e.g. a Dask client's, can be passed instead).
"""
