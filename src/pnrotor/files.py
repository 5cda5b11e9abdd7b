"""Files other than HDF5 (CSV tables, JSON summaries, figures) written whole or not at all: the light form of the one
crash-safe writer, :func:`pnrotor.io.atomic.replaced_on_success`, under its old name."""

from pnrotor.io.atomic import replaced_on_success

__all__ = ["replaced_on_success"]
