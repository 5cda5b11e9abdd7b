"""`FrameHistory`, the result of integrating an angular velocity, under its old name: it lives in
:mod:`pnrotor.results.runs` with the other result types."""

from pnrotor.results.runs import FrameHistory
from pnrotor.results.schema import short_repr

__all__ = ["FrameHistory", "short_repr"]
