"""A file grown in place, a piece at a time, each piece committed: what a process death (kill -9, a crash) leaves is
the file as of its last commit, never a torn one.

A :class:`JournaledFile` is a file-like object (what h5py's ``fileobj`` driver, or any writer of a binary file, asks
for) on a file whose first ``committed`` bytes hold its last committed state.  Bytes written beyond them go to the file
at once; bytes written over them (a format's headers, indexes and free-space records) are kept in memory, a page at a
time, until :meth:`JournaledFile.commit`, which writes the pages and the new length to the journal (a file beside,
replaced by a rename, so it is whole or absent), then over the file, then the journal again with the length alone.
:func:`recover` applies the journal again (idempotent) and cuts the file to the committed length: after a death during
a piece, the piece is gone and the rest is exactly as committed; after a death during a commit, the commit is
completed.  So each byte of a piece is written once (the pages, a few kB per piece, twice).

Like a file that is not fsynced, this survives the death of the process, not a power loss: the caller fsyncs what
must survive that (:mod:`pnrotor.io.atomic` before it publishes a finished file).
"""

import os
import struct
import zlib
from pathlib import Path

__all__ = ["JournaledFile", "recover"]

PAGE = 4096
"""Bytes of a page of the committed part kept in memory when written over."""
_HEADER = struct.Struct("<4sQQ")   # magic, the committed length, the number of pages
_MAGIC = b"pnj1"


class JournaledFile:
    """The file `path` (created if absent) opened for writing, its first `committed` bytes never written in place
    before :meth:`commit` (module docstring); call :func:`recover` first after a possible death."""

    def __init__(self, path, journal, committed):
        self.path, self.journal, self.committed = Path(path), Path(journal), committed
        self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
        self._pages, self._pos, self._length = {}, 0, committed

    # the methods of a binary file that h5py's fileobj driver calls
    def seek(self, offset, whence=os.SEEK_SET):
        self._pos = offset + (0, self._pos, self._length)[whence]
        return self._pos

    def tell(self):
        return self._pos

    def readinto(self, buffer):
        view = memoryview(buffer).cast("B")
        end = min(self._pos + len(view), self._length)
        n = max(end - self._pos, 0)
        data = os.pread(self._fd, n, self._pos) if n else b""
        view[:len(data)] = data
        view[len(data):n] = bytes(n - len(data))   # a range reserved but not yet written reads as zeros
        for page in range(self._pos // PAGE, (end - 1) // PAGE + 1) if n else ():
            data = self._pages.get(page)
            if data is not None:
                lo, hi = max(page * PAGE, self._pos), min(page * PAGE + len(data), end)
                if lo < hi:
                    view[lo - self._pos:hi - self._pos] = data[lo - page * PAGE:hi - page * PAGE]
        self._pos += n
        return n

    def read(self, size=-1):
        buffer = bytearray(max(self._length - self._pos, 0) if size < 0 else size)
        return bytes(buffer[:self.readinto(buffer)])

    def write(self, data):
        view = memoryview(data).cast("B")
        pos, n = self._pos, len(view)
        below = min(max(self.committed - pos, 0), n)   # the part over committed bytes: into pages
        for page in range(pos // PAGE, (pos + below - 1) // PAGE + 1) if below else ():
            kept = self._page(page)
            lo, hi = max(page * PAGE, pos), min(page * PAGE + len(kept), pos + below)
            kept[lo - page * PAGE:hi - page * PAGE] = view[lo - pos:hi - pos]
        done = below
        while done < n:   # the rest straight to the file
            done += os.pwrite(self._fd, view[done:], pos + done)
        self._pos = pos + n
        self._length = max(self._length, self._pos)
        return n

    def truncate(self, size=None):
        size = self._pos if size is None else size
        self._length = size
        if size >= self.committed:
            os.ftruncate(self._fd, size)
        return size

    def flush(self):
        pass

    def _page(self, page):
        if page not in self._pages:
            self._pages[page] = bytearray(os.pread(self._fd, min(PAGE, self.committed - page * PAGE), page * PAGE))
        return self._pages[page]

    def commit(self):
        """Make what was written since the last commit the file's committed state (module docstring)."""
        pages = sorted(self._pages.items())
        _record(self.journal, self._length, pages)
        _apply(self._fd, pages, self._length)
        if pages:   # applied: the journal keeps the length alone, so that no later recovery writes these pages again
            _record(self.journal, self._length, [])
        self.committed, self._pages = self._length, {}

    def close(self):
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def recover(path, journal):
    """The committed length of the file `path` after completing its last commit from `journal` (0 and no file
    without a journal: nothing was committed); a ValueError if the journal is damaged."""
    path, journal = Path(path), Path(journal)
    if not journal.exists():
        path.unlink(missing_ok=True)
        return 0
    record = journal.read_bytes()
    body, crc = record[:-4], record[-4:]
    if len(record) < _HEADER.size + 4 or struct.unpack("<I", crc)[0] != zlib.crc32(body) or body[:4] != _MAGIC:
        raise ValueError(f"{journal} is damaged: the file {path} cannot be restored to its last commit")
    _, length, count = _HEADER.unpack_from(body)
    pages, at = [], _HEADER.size
    for _ in range(count):
        page, size = struct.unpack_from("<QI", body, at)
        pages.append((page, body[at + 12:at + 12 + size]))
        at += 12 + size
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        _apply(fd, pages, length)
    finally:
        os.close(fd)
    return length


def _record(journal, length, pages):
    """Write the journal: the committed `length` and the `pages` [(page, bytes)], whole or not at all (a rename)."""
    record = _HEADER.pack(_MAGIC, length, len(pages)) + b"".join(
        struct.pack("<QI", page, len(data)) + bytes(data) for page, data in pages)
    temporary = journal.with_name(journal.name + ".new")
    temporary.write_bytes(record + struct.pack("<I", zlib.crc32(record)))
    os.replace(temporary, journal)


def _apply(fd, pages, length):
    for page, data in pages:
        os.pwrite(fd, data, page * PAGE)
    os.ftruncate(fd, length)
