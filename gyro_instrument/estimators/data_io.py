"""Measured data in and out: CSV and Parquet tables of instrument channels (docs/formats/csv.md).

``gyro-instrument estimate --data FILE --scene SCENE`` reads a table whose first column (or any
column) is ``time_s`` and whose other columns are ``<instrument>.<channel>``, matches them to the
scene's instruments and estimates from them with the same estimator as ``estimate`` and
``replay``. What each instrument type needs:

=====================================  ==================================================================
spherical / compound pendulum          ``x_east`` and ``y_north`` (m; divided by the scene's length to the
                                       deflections the sensor measures), or ``deflection_east`` and
                                       ``deflection_north`` (rad, x/l and y/l)
gyroscope with a directing line        its angle (``angle``; the gimbal: ``outer_angle`` or
(plane, cone, gimbal)                  ``inner_angle``, whichever the scene's configuration swings) and
                                       ``spin_rate`` (rad/s)
free gyroscope, Puiseux's body         nothing (not used by the estimator)
=====================================  ==================================================================

A gyroscope without ``spin_rate`` takes the scene's constant spin (its ``spin_rate_rad_s``, the
directing model's ρ0; noted). Samples may be missing (empty cell or ``nan``: left out, as a
dropout), irregular, duplicated or out of order (sorted by time, stable; the fits drop duplicated
stamps and say so); gaps and irregular sampling are noted (:func:`sampling_notes`). Times are
taken from the first valid sample when it is not 0 (a note says so). Fewer than two distinct
times is refused.

:class:`TableOptions` says how to read a table as users have it (``--time-column``,
``--time-unit``, ``--angle-unit``, ``--column NAME=SOURCE``, ``--separator``): see
:func:`load_table` and docs/formats/csv.md.
"""

import math
import os

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.table_read import (ANGLE_UNITS, ARROW_TIME_UNITS, SEPARATORS,  # noqa: F401
                                                   TIME_COLUMN, TIME_UNITS, TableOptions, import_pyarrow,
                                                   channel_meanings, load_table, read_table, table_kind)
from gyro_instrument.estimators.table_write import (BYTES_PER_VALUE, QUEUED_WRITES, ROWS_PER_WRITE,  # noqa: F401
                                                    SCALE_KEY, SCENE_KEY, TableWriter, output_bytes, scale_readings_text,
                                                    scene_of_table, scene_sidecar_path, scene_yaml_text, table_metadata,
                                                    table_scene, write_csv, write_table)


def _needs(inst):
    """Alternative column sets (each a tuple of channel names) that give this instrument's record
    (its observation's :meth:`~gyro_instrument.instruments.observation.Observation.table_columns`);
    () for an instrument the estimator does not use."""
    return inst.observation().table_columns()


#: A sampling interval more than this many times the median interval is a gap (noted).
GAP_FACTOR = 3.0

#: Intervals (gaps aside) spread by more than this fraction of the median are noted as irregular
#: sampling: above the jitter of a clock stamped to a whole ms at a few Hz (333/334 ms: 0.3 %).
IRREGULAR_SPREAD = 0.01


def sampling_notes(t) -> list:
    """Notes on the sampling of the sorted distinct times ``t`` (s): gaps (an interval above
    :data:`GAP_FACTOR` times the median interval: how many, the longest and where) and irregular
    sampling (the other intervals spread by more than :data:`IRREGULAR_SPREAD` of the median).
    [] for regular sampling."""
    dt = np.diff(np.asarray(t, dtype=float))
    if dt.size < 2:
        return []
    med = float(np.median(dt))
    notes = []
    gaps = dt > GAP_FACTOR * med
    if gaps.any():
        g = int(np.argmax(np.where(gaps, dt, -np.inf)))
        n = int(gaps.sum())
        notes.append(f"{n} gap{'s' if n > 1 else ''} longer than {GAP_FACTOR:g}x the median interval "
                     f"({med:.6g} s): {'longest ' if n > 1 else ''}{dt[g]:.6g} s at t = {t[g]:.6g} s "
                     f"(from the first sample)")
    rest = dt[~gaps]
    if rest.size and float(rest.max() - rest.min()) > IRREGULAR_SPREAD * med:
        notes.append(f"irregular sampling: intervals from {rest.min():.6g} to {rest.max():.6g} s "
                     f"(median {med:.6g} s{', gaps aside' if gaps.any() else ''}; spread above "
                     f"{IRREGULAR_SPREAD:.0%} of the median)")
    return notes


def _table_times(cols, path, field, notes) -> tuple:
    """The time column sorted and from its first sample: ``(t, keep, order, distinct)``, ``keep``
    the rows with a finite time, ``order`` their stable sort, ``distinct`` the sorted distinct
    times as read; the notes (rows left out, re-ordering, gaps and irregular sampling, time origin)
    appended to ``notes``."""
    t = np.asarray(cols[TIME_COLUMN], dtype=float)
    bad_t = ~np.isfinite(t)
    if bad_t.all():
        raise SceneError(field, path, f"column {TIME_COLUMN} holds no finite time")
    if bad_t.any():
        notes.append(f"{int(bad_t.sum())} rows without a finite {TIME_COLUMN} left out")
    keep = ~bad_t
    t = t[keep]
    distinct = np.unique(t)         # fewer than 2: refused once the columns are known to match the scene
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(order) < 0):
        reverse = bool(np.all(np.diff(t) <= 0))
        notes.append(f"rows {'in decreasing' if reverse else 'out of'} time order: sorted by {TIME_COLUMN}")
    t = t[order]
    notes.extend(sampling_notes(distinct - distinct[0]))
    t0 = float(t[0])
    if t0 != 0.0:
        notes.append(f"times taken from the first sample ({TIME_COLUMN} = {t0!r} s)")
        t = t - t0
    return t, keep, order, distinct


def records_from_table(insts, cols, path="data", field="--data") -> tuple:
    """Estimator records from table columns (see the module docstring).

    Returns
    -------
    records : dict
        instrument name -> record (``t`` and the measured channels), for the instruments matched.
    notes : list of str
        Instruments left out, columns not used, rows dropped, re-ordering, time origin.
    observation_s : float
        Time from the first to the last valid sample.

    Raises
    ------
    SceneError
        An instrument has some of its columns but not a complete set (the scene does not match the
        data: wrong type, or columns missing), an instrument's companion record has no column (a
        rotor-off swing), or no instrument the estimator uses has its columns.
    """
    from gyro_instrument.estimators.pipeline import estimable
    notes = []
    t, keep, order, distinct = _table_times(cols, path, field, notes)

    def col(name):
        return np.asarray(cols[name], dtype=float)[keep][order]

    records, used = {}, set()
    wanted = []
    for name, inst in insts.items():
        present = sorted(c.split(".", 1)[1] for c in cols if c.startswith(f"{name}."))
        options = _needs(inst)
        if not options:
            used.update(f"{name}.{c}" for c in present)
            records[name] = {"t": t.copy()}
            continue
        wanted.append(f"{name} ({inst.type_name}): " + " or ".join(
            "+".join(f"{name}.{c}" for c in opt) for opt in options))
        full = next((opt for opt in options if all(c in present for c in opt)), None)
        if full is None:
            if not present:
                notes.append(f"{name} ({inst.type_name}): no column in the data; left out")
                continue
            need = " or ".join(", ".join(f"{name}.{c}" for c in opt) for opt in options)
            raise SceneError(field, path, f"does not match the scene's {name} ({inst.type_name}): needs {need}; "
                                          f"the data has {', '.join(f'{name}.{c}' for c in present)}")
        used.update(f"{name}.{c}" for c in full)
        rec = {"t": t.copy()} | inst.observation().record_from_table(full, _reader(name, cols, col, used),
                                                                       t.size, notes)
        rec = _with_track(inst.observation(), rec, cols, col, used, name, notes)
        n_nan = int(sum((~np.isfinite(rec[c])).sum() for c in rec if c not in ("t", "angle")))
        if n_nan:
            notes.append(f"{name}: {n_nan} missing or NaN values left out")
        records[name] = rec
    _check_companions(insts, records, path, field)
    if not any(_needs(insts[n]) and estimable(insts[n]) for n in records):
        raise SceneError(field, path, "does not match the scene: no instrument's columns found; expected "
                                      + "; ".join(wanted) if wanted else
                                      "the scene has no instrument the estimator uses")
    if distinct.size < 2:
        raise SceneError(field, path, f"column {TIME_COLUMN} never increases: its {t.size} finite "
                                      f"time{'s are all' if t.size > 1 else ' is'} {float(distinct[0])!r}; "
                                      f"at least two distinct times are needed (a wrong --time-column?)")
    # columns the instrument writes but the estimator does not read (angle_rate, swing_azimuth ...)
    # are passed over silently; columns of no instrument or channel of the scene are noted
    known = {f"{n}.{c.name}" for n, inst in insts.items() for c in inst.COLUMNS}
    unknown = [c for c in cols if c != TIME_COLUMN and c not in used and c not in known]
    if unknown:
        shown = ", ".join(unknown[:8]) + (f" and {len(unknown) - 8} more" if len(unknown) > 8 else "")
        notes.append(f"columns matching no channel of the scene's instruments, not used: {shown}")
    t_ok = t[np.isfinite(t)]
    return records, notes, float(t_ok[-1] - t_ok[0]) if t_ok.size else 0.0


def _with_track(obs, rec, cols, col, used, name, notes) -> dict:
    """``rec`` with the ship's track an observation reads (``TRACK_KEYS``): the table's ``ship.<key>``
    columns, else the scene's ``motion:`` block (the observation's ``complete``, noted)."""
    if not obs.TRACK_KEYS:
        return rec
    from gyro_instrument.core.motion import SHIP
    missing = []
    for k in obs.TRACK_KEYS:
        if f"{SHIP}.{k}" in cols:
            used.add(f"{SHIP}.{k}")
            rec[k] = col(f"{SHIP}.{k}")
        else:
            missing.append(f"{SHIP}.{k}")
    if missing:
        notes.append(f"{name}: no column {', '.join(missing)}: the ship's track from the scene's motion block")
    return obs.complete(rec)


def _check_companions(insts, records, path, field) -> None:
    """Refuse a table without the columns of a record the estimator reads beside an instrument's own
    (:func:`~gyro_instrument.estimators.pipeline.missing_companions`: a rotor-off swing)."""
    from gyro_instrument.estimators.pipeline import missing_companions
    for name, key, other in missing_companions(insts, records):
        need = " or ".join("+".join(f"{other}.{c}" for c in opt) for opt in _needs(insts[other]))
        raise SceneError(field, path, f"has no column {need}: {name} reads its {key.replace('_', '-')} swing "
                                      f"from {other}")


#: Length units a logger may have written under ``x_east``/``y_north`` (metres): factor, name.
LENGTH_UNITS = ((100.0, "centimetres"), (1000.0, "millimetres"))


def _reader(name, cols, col, used):
    """``read(channel)``: the column ``<name>.<channel>`` as :func:`records_from_table` reads it (its
    valid rows, sorted), marked used; None when the table has no such column."""
    def read(channel):
        key = f"{name}.{channel}"
        if key not in cols:
            return None
        used.add(key)
        return col(key)
    return read


def _name_a_length_unit(exc, insts, cols) -> None:
    """A pendulum's amplitude refusal read from positions (``x_east``/``y_north``, metres divided by
    the scene's length): a ratio near 100 or 1000 is a length unit, not degrees — say that instead
    (there is no flag for it: the columns must be converted to metres)."""
    from gyro_instrument.estimators.adequacy import AMPLITUDE_FACTOR
    name, check = exc.check["instrument"], exc.check["check"]
    inst = insts.get(name)
    length = inst.observation().table_length_m() if inst is not None else None
    if check != "amplitude" or length is None or f"{name}.x_east" not in cols:
        return
    ratio = exc.check["value"] / exc.check["expected"] if exc.check.get("expected") else math.inf
    unit = next((u for f, u in LENGTH_UNITS if abs(math.log(ratio / f)) < math.log(2.0)), None)
    cause = (f"{name}.x_east/y_north look like {unit}, not metres: convert them to metres (or pass "
             f"--metres-per-pixel {1.0 / dict((u, f) for f, u in LENGTH_UNITS)[unit]:g})" if unit else
             f"{name}.x_east/y_north are metres divided by the scene's length_m ({length:g} m): "
             "check the length and the columns' unit (pixels of a camera: pass --metres-per-pixel S)")
    exc.restate(f"deflection amplitude {exc.check['value']:.6g} rad (positions / length_m) is {ratio:.3g}x the "
                 f"scene's release {exc.check['expected']:.6g} rad (at most {AMPLITUDE_FACTOR:g}x): {cause}")


def estimate_data(scene, path, field="--data", options=None) -> dict:
    """The ``estimate`` JSON object from a CSV or Parquet table of measured channels, read as
    ``options`` say (:class:`TableOptions`), with ``data`` (the file), ``observation_s`` (the
    data's span) and ``data_notes`` (what reading converted, then what the records dropped).

    Raises
    ------
    SceneError
        See :func:`load_table` and :func:`records_from_table`.
    """
    from gyro_instrument.estimators.adequacy import InadequateData
    from gyro_instrument.estimators.pipeline import estimate_records
    from gyro_instrument.scenes import build_instruments
    insts = build_instruments(scene)
    cols, read_notes = load_table(path, field, options, channel_meanings(insts))
    records, notes, span = records_from_table(insts, cols, path, field)
    notes = read_notes + notes
    try:
        result = estimate_records(scene, {n: insts[n] for n in records}, records)
    except InadequateData as exc:
        from gyro_instrument.estimators.time_advice import advise_time
        _name_a_length_unit(exc, insts, cols)
        advise_time(exc, options, cols[TIME_COLUMN], read_notes)   # from the column as written: never loops
        raise
    result["observation_s"] = span
    result["data"] = os.path.basename(path)
    if notes:
        result["data_notes"] = notes
    if not math.isfinite(span):
        result["observation_s"] = None
    return result
