"""Every north method on one record (:func:`north_methods`): the Schuler mean, Lavrov, the transit
method and the fit, each refused with its reason where the record cannot give it."""

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north.base import reversal_points
from gyro_instrument.estimators.north.fit import fit_record
from gyro_instrument.estimators.north.means import lavrov, schuler_mean
from gyro_instrument.estimators.north.timing import transit_method


def north_methods(t, u, noise_sigma_rad=None, mark_rad=None, drift=False, fit=True) -> tuple:
    """Every method on one record: ({name: NorthEstimate}, {name: why it was refused}).

    Names: ``schuler_mean`` and ``lavrov`` (on the reversal points, σ propagated from their σ),
    ``transit`` (the mark: ``mark_rad``, default the Schuler mean — a mark set near the centre, as
    a surveyor first sets the theodolite near north from a rough reversal-point reading) and ``fit``
    (with a linear drift of the centre when ``drift``: the centre at the mean sample time; left out
    when not ``fit``).
    """
    out, refused = {}, {}
    try:
        rp = reversal_points(t, u, noise_sigma_rad)
    except SceneError as exc:                      # too short for two reversal points: every method refused
        return out, {k: str(exc) for k in ("schuler_mean", "lavrov", "transit", "fit")}
    runs = {"schuler_mean": lambda: schuler_mean(rp.readings_rad, rp.sigmas_rad),
            "lavrov": lambda: lavrov(rp.readings_rad, rp.sigmas_rad),
            "transit": lambda: transit_method(t, u, out["schuler_mean"].centre_rad if mark_rad is None
                                              else mark_rad, noise_sigma_rad, rp),
            "fit": lambda: fit_record(t, u, noise_sigma_rad, drift=drift)}
    if not fit:                                    # the estimate's fit is the exact one (.exact)
        runs.pop("fit")
    for name, run in runs.items():
        try:
            out[name] = run()
        except KeyError:                           # transit's mark is the Schuler mean's centre
            refused[name] = f"its mark is the Schuler mean's centre, refused: {refused.get('schuler_mean')}"
        except (SceneError, np.linalg.LinAlgError) as exc:
            refused[name] = str(exc)
    return out, refused
