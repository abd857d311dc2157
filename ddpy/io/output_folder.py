"""The output folder of a run: the checks of its path before anything is written, and the
lock that gives one run at a time the folder (docs/running.md).

>>> from ddpy.io.output_folder import FolderLock, check_output_folder
>>> check_output_folder("runs/strip")             # doctest: +SKIP
>>> with FolderLock("runs/strip"):                 # doctest: +SKIP
...     ...  # write the results; another run on the folder is refused meanwhile

The lock is the kernel's (``flock`` on ``.ddpy.lock`` in the folder, which holds the pid of
the run that has it): it lasts while the run's process lives and goes with it, however the
process ends, so the lock file a killed run leaves is taken over by the next run.
"""

from __future__ import annotations

import errno
import fcntl
import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

__all__ = ["LOCK", "PSEUDO_FILESYSTEMS", "RESULT_MODE", "FolderInUse", "FolderLock",
           "OutputFolderError", "atomic_write", "check_output_folder", "output_path",
           "temporary_beside"]

#: Permissions of every file a run writes (results, XDMF, checkpoint, status): readable by
#: all, so that a colleague can open them.
RESULT_MODE = 0o644

#: The lock file in an output folder.
LOCK = ".ddpy.lock"
#: File-system types of the kernel's own views (processes, devices, control groups...):
#: nothing written there is kept as a file.
PSEUDO_FILESYSTEMS = frozenset({
    "autofs", "binfmt_misc", "bpf", "cgroup", "cgroup2", "configfs", "debugfs", "devpts",
    "devtmpfs", "efivarfs", "fusectl", "hugetlbfs", "mqueue", "nsfs", "proc", "pstore",
    "rpc_pipefs", "securityfs", "selinuxfs", "sysfs", "tracefs"})


def temporary_beside(path: Path, prefix: str, suffix: str = "") -> tuple[int, str]:
    """A new temporary file in ``path``'s folder, to be renamed over ``path`` once written
    (an atomic replacement): its descriptor and name, with RESULT_MODE. mkstemp makes it
    0600, which the rename would pass on to ``path``."""
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=prefix, suffix=suffix)
    try:
        os.fchmod(fd, RESULT_MODE)
    except OSError:
        os.close(fd)
        Path(name).unlink(missing_ok=True)
        raise
    return fd, name


@contextmanager
def atomic_write(path: Path, binary: bool = False) -> Iterator[IO[Any]]:
    """A file object whose contents replace ``path`` in one step when the block ends: written
    to a temporary beside it, flushed to the disk (fsync), renamed over it. On any failure
    (a full disk, an interrupt) the temporary goes and ``path`` keeps its last complete
    version; an OSError names ``path``, not the temporary."""
    path = Path(path)
    try:
        fd, tmp = temporary_beside(path, f".{path.name}-")
    except OSError as error:
        raise OSError(error.errno, error.strerror, str(path)) from error
    try:
        with os.fdopen(fd, "wb" if binary else "w") as out:
            yield out
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except OSError as error:
        Path(tmp).unlink(missing_ok=True)
        raise OSError(error.errno, error.strerror, str(path)) from error
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class OutputFolderError(RuntimeError):
    """An output folder that cannot take a run's results: empty, a file system's root, not a
    folder, not writable, a pseudo-filesystem, too full, or in use by another run."""


class FolderInUse(OutputFolderError):
    """The folder is locked by another run (``pid`` None when its lock file holds none)."""

    def __init__(self, folder: Path, pid: int | None) -> None:
        holder = f"process {pid}" if pid is not None else "a process that has not written " \
            "its pid yet"
        super().__init__(f"{folder}: in use by another ddpy run ({holder}); nothing in it was "
                         "changed: wait for that run to end, or choose another --output")
        self.folder, self.pid = folder, pid


def output_path(output: str | os.PathLike[str]) -> Path:
    """``output`` as a path; an empty name (which Path would take as the working folder)
    is refused."""
    if not os.fspath(output).strip():
        raise OutputFolderError("the output folder's name is empty; name a folder (--output "
                                "DIR)")
    return Path(output)


def _existing_ancestor(output: Path) -> Path:
    """The folder itself if it exists, else its nearest existing ancestor; a path through a
    file or a dangling symbolic link is refused."""
    folder = output
    while not folder.exists():
        if folder.is_symlink():
            raise OutputFolderError(f"{output}: {folder} is a symbolic link to nothing; the "
                                    "output must be a folder")
        if folder == folder.parent:
            break
        folder = folder.parent
    if not folder.is_dir():
        if folder == output:
            raise OutputFolderError(f"{output}: a file is there; the output must be a folder")
        raise OutputFolderError(f"{output}: {folder} is a file, not a folder")
    return folder


def _mount_of(folder: Path) -> tuple[str, str] | None:
    """The mount point and file-system type of the file system holding ``folder``
    (Linux: /proc/self/mountinfo, matched by device number); None where unknown."""
    try:
        device = os.stat(folder).st_dev
        lines = Path("/proc/self/mountinfo").read_text().splitlines()
    except OSError:
        return None
    wanted = f"{os.major(device)}:{os.minor(device)}"
    where = folder.resolve()
    found: list[tuple[bool, int, str, str]] = []
    for line in lines:
        fields = line.split()
        if len(fields) < 7 or fields[2] != wanted or "-" not in fields[6:]:
            continue
        after = fields.index("-", 6)
        if after + 1 < len(fields):
            # The mount point's blanks and backslashes are written as octal escapes.
            point = re.sub(r"\\([0-7]{3})", lambda m: chr(int(m.group(1), 8)), fields[4])
            holds = where == Path(point) or Path(point) in where.parents
            found.append((holds, len(point), point, fields[after + 1]))
    if not found:
        return None
    _, _, point, kind = max(found)  # the innermost mount holding the folder
    return point, kind


def check_output_folder(output: str | os.PathLike[str], needed: int = 0) -> Path:
    """Refuse (OutputFolderError, one line) an output folder that cannot take results:
    an empty name, the root of the file system, a path through a file, a folder on a
    pseudo-filesystem (/proc, /sys...), one that cannot be written, or one whose file
    system (that of its nearest existing ancestor) has less than ``needed`` bytes free.
    Nothing is written. Returns the output as a Path."""
    output = output_path(output)
    if output.resolve() == output.resolve().parent:
        raise OutputFolderError(f"{output}: the root of the file system is not a place for "
                                "results; name a folder (--output DIR)")
    folder = _existing_ancestor(output)
    mount = _mount_of(folder)
    try:
        usage = shutil.disk_usage(folder)
    except OSError as error:
        raise OutputFolderError(f"{output}: {folder} cannot be examined "
                                f"({error.strerror or error})") from None
    # Where the type is unknown, a file system of no size at all is taken for one.
    if mount[1] in PSEUDO_FILESYSTEMS if mount else usage.total == 0:
        what = f"a {mount[1]} pseudo-filesystem" if mount else "a file system of no size"
        raise OutputFolderError(f"{output}: {mount[0] if mount else folder} is {what}, not a "
                                "place for results; choose another --output")
    if not os.access(folder, os.W_OK | os.X_OK):
        read_only = os.statvfs(folder).f_flag & os.ST_RDONLY
        why = "its file system is mounted read-only" if read_only else "permission denied"
        raise OutputFolderError(f"{output}: {folder} is not writable ({why}); choose another "
                                "--output")
    if usage.free < needed:
        raise OutputFolderError(f"{folder}: {usage.free / 1e6:.3g} MB free, the results of "
                                f"this mesh need at least {needed / 1e6:.3g} MB to start; free "
                                "some space or choose another --output")
    return output


class FolderLock:
    """The exclusive lock of one run on an output folder (an existing folder): ``flock`` on
    its ``.ddpy.lock``, which holds the pid of the holder. :meth:`acquire` refuses a folder
    another process holds (FolderInUse) without changing anything in it; :meth:`release`
    removes the lock file. Use as a context manager."""

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.folder = Path(folder)
        self.path = self.folder / LOCK
        self._fd: int | None = None

    def acquire(self) -> None:
        """Take the lock or raise FolderInUse (OutputFolderError for a lock file that cannot
        be opened or locked)."""
        if self._fd is not None:
            return
        while True:
            try:
                # No O_TRUNC: the file of a holder keeps its pid for the next contender.
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW,
                             0o644)
            except OSError as error:
                raise OutputFolderError(f"{self.path}: cannot be opened as the run's lock "
                                        f"file ({error.strerror or error}); remove it, or "
                                        "choose another --output") from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as error:
                pid = _read_pid(fd)
                os.close(fd)
                if error.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    raise FolderInUse(self.folder, pid) from None
                raise OutputFolderError(f"{self.path}: cannot be locked ({error.strerror}); "
                                        "choose an --output on a local file system") from None
            # The holder before may have removed the file between our open and our lock:
            # then the file locked is no longer the folder's, and a third run may hold that.
            if _is_file_of(self.path, fd):
                break
            os.close(fd)
        try:  # the pid only informs a contender; the lock is the kernel's (a full disk)
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError:
            pass
        self._fd = fd

    def release(self) -> None:
        """Remove the lock file and give the lock back (removed while held: see acquire)."""
        if self._fd is None:
            return
        try:  # only our own file: not one a later run made after ours was removed by hand
            if _is_file_of(self.path, self._fd):
                self.path.unlink()
        except OSError:
            pass  # a folder that became read-only: the kernel's lock goes all the same
        os.close(self._fd)
        self._fd = None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def __enter__(self) -> FolderLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _read_pid(fd: int) -> int | None:
    """The pid a lock file holds, None when it holds none."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def _is_file_of(path: Path, fd: int) -> bool:
    """Whether ``path`` names the file open as ``fd`` (not a file made there since)."""
    try:
        current = os.stat(path, follow_symlinks=False)
    except OSError:
        return False
    mine = os.fstat(fd)
    return (current.st_dev, current.st_ino) == (mine.st_dev, mine.st_ino)
