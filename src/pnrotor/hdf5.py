"""`pnrotor.hdf5` is :mod:`pnrotor.io.hdf5` (pnrotor's HDF5 files, one format of :mod:`pnrotor.io`) under the name its
users know: ``pnrotor.hdf5.read``, ``.write``, ``.batch``, ``.check`` ... are the same objects."""

import sys

from pnrotor.io import hdf5

sys.modules[__name__] = hdf5
