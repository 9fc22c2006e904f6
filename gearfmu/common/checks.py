"""Input checks shared by the physics modules and the solvers: one place for "a finite number,
positive or non-negative", raising the caller's own error class with the field's name."""
from __future__ import annotations

import math


def finite_number(name, value, *, positive=False, nonneg=False, error=ValueError) -> float:
    """``value`` as a finite float (> 0 with ``positive``, >= 0 with ``nonneg``); otherwise
    ``error`` with a message naming ``name`` and the reason."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise error(f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise error(f"{name}: must be finite, got {value!r}")
    if positive and v <= 0:
        raise error(f"{name}: must be > 0, got {value!r}")
    if nonneg and v < 0:
        raise error(f"{name}: must be >= 0, got {value!r}")
    return v
