"""Figures (kept for existing imports): everything lives in :mod:`sindyship.plotting`."""

from __future__ import annotations

from . import plotting as _plotting

__all__ = list(_plotting.__all__)


def __getattr__(name: str):
    return getattr(_plotting, name)
