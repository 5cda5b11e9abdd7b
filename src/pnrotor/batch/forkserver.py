"""Imported by multiprocessing's fork server of a batch (``set_forkserver_preload``), before the PN code: the
server then dies with the batch process, and with it the workers it forked (each dies with its parent,
:func:`pnrotor.processes.die_with_parent`), so a batch killed with kill -9 leaves no process behind."""

from pnrotor.processes import die_with_parent

die_with_parent()
