"""JSON-ready values: what every ``--json`` output and recorded estimate passes through."""

import math

import numpy as np


def to_jsonable(x) -> object:
    """Floats for JSON: non-finite values become None (never NaN or Infinity); a complex number
    becomes ``{"real": ..., "imag": ...}`` (a real one its real part)."""
    if isinstance(x, dict):
        return {k: to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, (complex, np.complexfloating)):   # e.g. the roots of an unstable motion's eq.
        return x.real if x.imag == 0 else {"real": to_jsonable(x.real), "imag": to_jsonable(x.imag)}
    return x
