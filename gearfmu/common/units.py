"""Unit conversions the layers share (everything inside gearfmu is SI; the scene speaks rpm)."""
from __future__ import annotations

import math

__all__ = ["RPM_TO_RAD_S"]

#: rev/min -> rad/s
RPM_TO_RAD_S = 2.0 * math.pi / 60.0
