"""sindyship: discover a ship's manoeuvring equations from trajectory data."""

from __future__ import annotations

__version__ = "0.1.0"
