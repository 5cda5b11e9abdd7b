"""Crash-safe writing of any file: built under a temporary name beside its target, published whole or not at all.

:func:`replaced` gives a new temporary file ``NAME.HOST.PID.XXXXXXXX.pnrotor-tmp`` beside the target (or a copy of the
target); leaving the block without an exception fsyncs it (durable writes; the writeback of large pieces can start in
the background, :class:`Writeback`, while the writer goes on), then publishes it as the target: linked to its name
(``os.link``) if it is new, so that of two writers of a new path exactly one succeeds, or renamed over it
(``os.replace``) with overwrite, then fsyncs the folder.  Any exception, Ctrl-C included (SIGINT, SIGTERM and SIGHUP
raise KeyboardInterrupt while the file is written, :class:`Interrupts`), removes the temporary file and leaves the
target as it was; only a hard kill (SIGKILL, power loss) can leave one, which the next durable write of that target on
the same host removes if its writer is no longer alive.  :func:`replaced_on_success` is the light form for tables,
summaries and figures: the same temporary names (with the target's suffix, which matplotlib reads) and publication by
``os.replace``, without fsyncs or signal handling.

Every format of :mod:`pnrotor.io` writes through this module (:mod:`pnrotor.io.hdf5` opens its HDF5 file on the
temporary name).  Imports nothing of pnrotor but :mod:`pnrotor.signals`.
"""

import errno
import os
import re
import secrets
import shutil
import signal
import socket
import threading
from contextlib import contextmanager, suppress
from pathlib import Path

from pnrotor import signals

__all__ = ["replaced", "replaced_on_success", "check_target", "check_space", "temporary_beside", "publish", "fsync",
           "Writeback", "Interrupts", "write_failure", "HOST", "TEMPORARY_SUFFIX", "METADATA_MARGIN"]


@contextmanager
def replaced(path, overwrite, copy=False, durable=True):
    """Yield ``(temporary, writeback)``: a new empty file beside `path`, or with `copy` a copy of `path`, to write,
    and its :class:`Writeback` (None unless `durable`).  Leaving without an exception fsyncs it (if `durable`) and
    publishes it as `path` (:func:`publish`: refused if `path` appeared meanwhile and not `overwrite`), then fsyncs
    the folder; an exception removes it, and a failed system call the writer reports as ``errno = N`` (HDF5's
    reports, :func:`write_failure`) becomes one OSError naming `path`."""
    path = Path(path)
    temporary = temporary_beside(path, sweep=durable)
    writeback = Writeback(temporary) if durable else None
    try:
        with Interrupts() as interrupts:
            if copy:
                shutil.copyfile(path, temporary)
            yield temporary, writeback
            if writeback:
                writeback.join()
                fsync(temporary)
            interrupts.check()
            publish(temporary, path, overwrite)
    except BaseException as error:
        if writeback:
            writeback.join()
        temporary.unlink(missing_ok=True)
        code = write_failure(error, temporary)
        if code is not None:
            raise OSError(code, f"no space left on the device of {path.parent} while writing {path.name}"
                          if code == errno.ENOSPC else f"{os.strerror(code)} while writing {path}") from None
        raise
    if durable:
        fsync(path.parent)


@contextmanager
def replaced_on_success(path):
    """A temporary path beside ``path`` (its name ending in ``path``'s suffix, so that matplotlib infers the format)
    to write; on leaving without an exception it replaces ``path``, else it is removed (module docstring)."""
    path = Path(path)
    temporary = temporary_beside(path, sweep=False, suffix=path.suffix)
    try:
        yield temporary
        publish(temporary, path, overwrite=True)
    except BaseException:
        with suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


HOST = socket.gethostname().replace(".", "-").replace("/", "-") or "host"


TEMPORARY_SUFFIX = ".pnrotor-tmp"


def check_target(path, overwrite):
    """Raise unless `path` can be written: not a folder, in a folder that exists, new unless `overwrite`."""
    if path.is_dir():
        raise IsADirectoryError(f"{path} is a folder; give a file name such as {path / 'run.h5'}")
    if not path.parent.is_dir():
        raise FileNotFoundError(f"folder {path.parent} does not exist (writing {path}); create it first")
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True (--overwrite) to replace it")


METADATA_MARGIN = 2 ** 20
"""Bytes of free space `check_space` keeps beyond a run's arrays, for HDF5's metadata (a run's groups and
attributes take tens of kB)."""


def check_space(path, need, compression=None):
    """An `OSError` (ENOSPC) naming the folder of `path` and the sizes if `need` bytes of arrays (`_run_bytes`, the
    uncompressed size: what the file holds, and an upper bound of a compressed file's) and `METADATA_MARGIN` do
    not fit in its free space: a full disk found before a byte is written, not in the middle of a write, where
    HDF5 fails badly (a compressed write to a full tmpfs crashed the process with SIGSEGV after its error;
    `Batch.copy_from` with a few kB free, a double free in HDF5's object copy)."""
    free = shutil.disk_usage(Path(path).parent).free
    if need + METADATA_MARGIN > free:
        raise OSError(errno.ENOSPC, f"no space for {Path(path).name} in {Path(path).parent}: its arrays need "
                                    f"{_size(need)}{' before compression' * bool(compression)} and its metadata up "
                                    f"to {_size(METADATA_MARGIN)}, {_size(free)} are free")


def _size(n):
    return f"{n / 2 ** 20:.1f} MiB" if n >= 2 ** 20 else f"{n / 2 ** 10:.1f} KiB"


def temporary_beside(path, sweep=True, suffix=""):
    """Create and return an empty, new file ``NAME.HOST.PID.XXXXXXXX.pnrotor-tmp`` (then `suffix`) in the folder of
    `path`, after removing those of `path` that writers on this host left when they died (`_sweep`; not for scratch
    files, written by the thousand into one folder, where listing it each time would cost N²)."""
    if sweep:
        _sweep(path)
    while True:
        temporary = path.with_name(f"{path.name}.{HOST}.{os.getpid()}.{secrets.token_hex(4)}{TEMPORARY_SUFFIX}{suffix}")
        try:
            os.close(os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
        except FileExistsError:
            continue
        return temporary


def _sweep(path):
    """Remove the temporary files of `path` whose writer ran on this host and is no longer alive (a kill -9
    or a power loss leaves them); those of live writers, of other hosts and anything else are kept."""
    prefix = f"{path.name}.{HOST}."
    try:
        names = os.listdir(path.parent)
    except OSError:
        return
    for name in names:
        if not (name.startswith(prefix) and name.endswith(TEMPORARY_SUFFIX)):
            continue
        pid = name[len(prefix):].split(".", 1)[0]
        if pid.isdigit() and not _alive(int(pid)):
            try:
                (path.parent / name).unlink()
            except (IsADirectoryError, PermissionError, FileNotFoundError):
                pass


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    return True


def fsync(path, sync=os.fsync):
    """``sync`` the file at ``path``: os.fsync, or os.fdatasync for `Writeback`'s background flush of the data
    (the final fsync writes the rest)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        sync(fd)
    finally:
        os.close(fd)


class Writeback:
    """Background fsyncs of a file being written: `start` begins one in a thread unless one is running. The
    final fsync stays the caller's (it waits for the pages these started too); each thread opens the file
    itself, so none touches a descriptor of the writer, and ignores errors (the file may be gone)."""

    def __init__(self, path):
        self.path, self._thread = path, None

    def start(self):
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._sync, name="pnrotor-writeback", daemon=True)
            self._thread.start()

    def join(self):
        if self._thread is not None:
            self._thread.join()

    def _sync(self):
        # a signal the kernel hands to this thread would wait for the main thread to return to Python: a
        # Ctrl-C or SIGTERM during a long sleep or write there went unseen (a writer killed with SIGINT
        # under load still ran 60 s later); blocked here, every signal goes to the main thread
        signal.pthread_sigmask(signal.SIG_BLOCK, signal.valid_signals())
        try:
            fsync(self.path, os.fdatasync)
        except OSError:
            pass


class Interrupts:
    """While a file is written (in the main thread): SIGINT, SIGTERM and SIGHUP raise KeyboardInterrupt at
    once, so the temporary file is removed (SIGTERM's and SIGHUP's default would kill the process and leave
    it), and are remembered: one that Python swallowed because it arrived inside h5py's cleanup callbacks
    ("Exception ignored ... KeyboardInterrupt") is raised again by `check` before the file is published.  A
    signal set to be ignored, or that the program handles, is left as it is (`pnrotor.signals`)."""

    def __init__(self):
        self.seen, self.previous = None, {}

    def __enter__(self):
        self.previous = signals.take(self._handle)
        return self

    def _handle(self, signum, frame):
        self.seen = signum
        raise KeyboardInterrupt

    def check(self):
        if self.seen is not None:
            raise KeyboardInterrupt

    def __exit__(self, *exc):
        signals.restore(self.previous)
        return False


def publish(temporary, path, overwrite):
    """Give the finished `temporary` file the name `path`: os.replace with `overwrite`, else os.link, which
    fails if `path` exists at that instant, so of two writers of a new path exactly one succeeds (a check
    then a rename let both report success); then the temporary name is removed."""
    if overwrite:
        os.replace(temporary, path)
        return
    message = f"{path} appeared while it was written; pass overwrite=True (--overwrite) to replace"
    try:
        os.link(temporary, path)
    except FileExistsError:
        raise FileExistsError(message) from None
    except OSError:  # a filesystem without hard links: check, then rename (not atomic)
        if path.exists():
            raise FileExistsError(message) from None
        os.replace(temporary, path)
        return
    os.unlink(temporary)


def write_failure(error, temporary):
    """The errno of HDF5's report of a failed system call on the file being written, a RuntimeError or OSError of
    many lines holding ``errno = N`` (a full disk, a file-size limit, a quota), or None: not for a report that
    names another file (``name = '...'``: one the caller opened in the block, a missing source, say)."""
    if not isinstance(error, (OSError, RuntimeError)):
        return None
    text = str(error)
    code = re.search(r"errno = (\d+)", text)
    others = [name for name in re.findall(r"name = '([^']*)'", text) if Path(name).name != temporary.name]
    return int(code.group(1)) if code and not others else None
