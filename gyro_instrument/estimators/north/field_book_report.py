"""The ``north`` block of a field book (``estimate --reversal-points FILE [--scene SCENE]``; issue 33 item 5).

:func:`field_book_block` reads the book (:mod:`.field_book`), takes from the scene, when one is
given, its horizontal gyroscope's latitude (refused where the directing torque n cos(latitude)
vanishes) and its tape (D_B/D_K from the scene instrument's ``tape_ratio()`` at that latitude, the
tape zero on its scale), reduces, and writes the block of msg_docs/estimate.md: degrees as before,
plus the d°m′s″ string and gon of the mount azimuth and of the circle reading of north (the readings
are clockwise circle readings, so north reads −mount, in [0, 360°)), the printed triple means, the
missed and the outlying turning points.
"""

import math

from gyro_instrument.core.angle_formats import format_angle
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators import north
from gyro_instrument.estimators.north.field_book import book_schuler_mean, outliers, read_field_book, reduce_field_book, triple_means
from gyro_instrument.estimators.north.block import FieldBookBlock, MissedPoint, Outlier
from gyro_instrument.estimators.north.estimate import arcsec_or_none, method_entry

#: |cos(latitude)| below which the directing torque is taken to vanish (cos 90° in floating point is 6e-17)
POLE_COS = 1e-12


def angle_fields(prefix, deg) -> dict:
    """``{<prefix>_deg, <prefix>_dms, <prefix>_gon}`` of an azimuth or circle reading in degrees: degrees
    as given, the d°m′s″ string rounded to 0.1″ and the gon value, both in [0, 360°) / [0, 400 gon)."""
    return {f"{prefix}_deg": deg, f"{prefix}_dms": format_angle(deg, "dms"),
            f"{prefix}_gon": (deg % 360.0) * 400.0 / 360.0 % 400.0}


def _north_fields(centre_rad) -> dict:
    mount = math.degrees(north.mount_azimuth_rad(centre_rad))
    return angle_fields("mount_azimuth", mount) | angle_fields("north_reading", math.degrees(centre_rad) % 360.0)


def scene_gyroscope(scene) -> tuple:
    """(name, instrument, notes) of the scene's first horizontal gyroscope with its rotor on.

    Raises
    ------
    SceneError
        No such instrument; a latitude where the directing torque vanishes (the pole: |cos| < POLE_COS),
        or no ``earth_rotation``.
    """
    from gyro_instrument.scenes import build_instruments
    found = [(n, i) for n, i in build_instruments(scene).items()
             if hasattr(i, "tape_ratio") and i.p.plane == "horizontal" and not i.is_cone and i.p.spin_rate_rad_s]
    if not found:
        raise SceneError("--scene", scene.name, "has no horizontal plane_gyroscope with its rotor on: a field "
                                                "book's north uses its latitude and tape; leave --scene out for "
                                                "the raw reduction")
    name, inst = found[0]
    lat = scene.site.latitude_deg
    if abs(math.cos(math.radians(lat))) < POLE_COS or not inst.frame_rotates():
        raise SceneError("site.latitude_deg", lat, "the directing torque n cos(latitude) vanishes there (a "
                                                   "horizontal gyroscope at a pole, or without earth_rotation): "
                                                   "no north from a field book; a latitude in (-90, 90)")
    notes = [f"scene {scene.name}: instrument {name} at latitude {lat:g}"
             + (f" (the first of {len(found)} horizontal gyroscopes)" if len(found) > 1 else "")]
    return name, inst, notes


def _scene_tape(name, inst) -> dict | None:
    """The scene's tape in the book's clockwise readings: zero −Z0, drift −Ż (the record reads
    counter-clockwise, :mod:`.estimate`); None without a tape."""
    D_B, Z0, dZ = inst.tape
    if not D_B:
        return None
    return {"instrument": name, "ratio": inst.tape_ratio(), "zero_rad": -Z0, "drift_rad_s": -dZ,
            "sine_law": inst.restoring_law() is not None}


def _tape_entry(tape) -> dict:
    zero = math.degrees(tape["zero_rad"])
    out = {k: v for k, v in tape.items() if k not in ("zero_rad", "zero_sigma_rad")}
    return out | angle_fields("zero_reading", zero) | {"zero_sigma_arcsec": arcsec_or_none(tape["zero_sigma_rad"])}


def _methods(ests, book) -> dict:
    out = {}
    for k, v in ests.items():
        out[k] = method_entry(v).to_json() | _north_fields(v.centre_rad)
    ks, m = triple_means(book.on)
    out["schuler_mean"]["triple_means"] = [
        {"turning_points": [int(k) + book.on.first_number + j for j in range(3)]} | angle_fields("mean", math.degrees(x))
        for k, x in zip(ks, m)]
    return out


def field_book_block(path, angle_unit=None, time_unit=None, scene=None, separator=None, division_rad=None) -> dict:
    """The ``north`` block of a field book (module docstring): the JSON of a :class:`.block.FieldBookBlock`.

    Parameters
    ----------
    path : str
    angle_unit, time_unit, separator, division_rad
        As :func:`.field_book.read_field_book`.
    scene : Scene, optional
        Its horizontal gyroscope's latitude and tape (:func:`scene_gyroscope`); None: the book alone.

    Raises
    ------
    SceneError
        The book's bad input (:func:`.field_book.read_field_book`); a scene without a horizontal
        gyroscope or at a latitude where the directing torque vanishes.
    """
    book = read_field_book(path, angle_unit, time_unit, separator=separator, division_rad=division_rad)
    notes, scene_tape, inst_name = list(book.notes), None, None
    if scene is not None:
        inst_name, inst, more = scene_gyroscope(scene)
        scene_tape, notes = _scene_tape(inst_name, inst), notes + more
    ests, tape, more = reduce_field_book(book, scene_tape)
    head = ests["schuler_mean"]
    found = outliers(book.on, book_schuler_mean(book.on).centre_rad)         # about the swing's own centre
    if tape is None and book.off is not None:
        reduction = "raw: the tape's pull is NOT removed (its readings lack the times of both swings, or are fewer " \
                    "than 3, and the scene has no tape)"
    elif tape is None:
        reduction = "raw: no tape in the book" + (" or the scene" if scene is not None else " and no scene") \
                    + " (the swing centre is north's reading)"
    else:
        reduction = f"tape removed ({tape['source']}; exact relation N = c - atan(x (Z - c)))"
    return FieldBookBlock(
        instrument=None, field_book=str(path), scene=None if scene is None else scene.name,
        scene_instrument=inst_name, latitude_deg=None if scene is None else scene.site.latitude_deg,
        **_north_fields(head.centre_rad), sigma_arcsec=arcsec_or_none(head.sigma_rad), crlb_arcsec=None,
        method="schuler_mean", reduction=reduction, tape=None if tape is None else _tape_entry(tape),
        methods=_methods(ests, book), turning_points=int(book.on.index.size),
        missed=[MissedPoint(**m) for m in book.on.missed], outliers=[Outlier(**o) for o in found], refused={},
        notes=notes + more + [f"{book.on.index.size} turning points read in {book.angle_unit}; the readings "
                              f"are the circle's, clockwise: north reads north_reading = -mount_azimuth"]).to_json()
