"""Write a set of output files all-or-nothing: temp files beside each target, then os.replace with rollback."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path


@dataclasses.dataclass
class _Staged:
    """One target during a transaction: its temp file, its backup (if it existed) and whether it was replaced."""

    target: Path
    temp: Path
    backup: Path | None = None
    replaced: bool = False


def _current_umask() -> int:
    # os.umask can only be read by setting it; restore it at once.
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def new_file_mode() -> int:
    """The mode an ordinary new file gets (0o666 less the umask, 0644 usually); mkstemp's temp files are 0600."""
    return 0o666 & ~_current_umask()


def _make_dirs(folders: list[Path], created: list[Path]) -> None:
    """Create missing folders, recording each in `created` (deepest last) so a failure can remove them again."""
    for folder in folders:
        missing: list[Path] = []
        probe = folder
        while not probe.exists() and probe != probe.parent:
            missing.append(probe)
            probe = probe.parent
        for path in reversed(missing):
            path.mkdir()
            created.append(path)


@contextlib.contextmanager
def _removed_on_failure(path: Path) -> Iterator[None]:
    """Remove `path` if the block fails, so that no half-made temp or backup file is left beside a target."""
    try:
        yield
    except BaseException:
        with contextlib.suppress(OSError):
            path.unlink()
        raise


def _write_temp(target: Path, data: bytes, mode: int) -> Path:
    fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    temp = Path(name)
    with _removed_on_failure(temp):
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(temp, mode)
    return temp


def _backup(target: Path) -> Path | None:
    """A hard link (or copy) of an existing target, so a half-done commit can be rolled back."""
    if not target.exists():
        return None
    fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".bak")
    os.close(fd)
    backup = Path(name)
    with _removed_on_failure(backup):
        backup.unlink()
        try:
            os.link(target, backup)
        except OSError:
            shutil.copy2(target, backup)
    return backup


def _rollback(staged: list[_Staged], created_dirs: list[Path]) -> None:
    for item in staged:
        with contextlib.suppress(OSError):
            if item.replaced:
                if item.backup is not None:
                    os.replace(item.backup, item.target)
                else:
                    item.target.unlink()
            item.temp.unlink(missing_ok=True)
            if item.backup is not None:
                item.backup.unlink(missing_ok=True)
    for folder in reversed(created_dirs):
        with contextlib.suppress(OSError):
            folder.rmdir()


def _fsync_dir(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def write_files_atomically(files: dict[Path, bytes | str]) -> None:
    """Write every file or none: on any failure the previous files are left as they were and no temp files remain.

    `str` contents are written as UTF-8 exactly as given (no newline translation). Missing
    target folders are created (and removed again on failure). The original exception is
    re-raised after clean-up.
    """
    items = [(Path(path), data.encode("utf-8") if isinstance(data, str) else bytes(data)) for path, data in files.items()]
    mode = 0o666 & ~_current_umask()
    staged: list[_Staged] = []
    created_dirs: list[Path] = []
    try:
        _make_dirs(sorted({target.parent for target, _ in items}), created_dirs)
        for target, data in items:
            staged.append(_Staged(target=target, temp=_write_temp(target, data, mode)))
        for item in staged:
            item.backup = _backup(item.target)
        for item in staged:
            os.replace(item.temp, item.target)
            item.replaced = True
    except BaseException:
        _rollback(staged, created_dirs)
        raise
    for item in staged:
        if item.backup is not None:
            with contextlib.suppress(OSError):
                item.backup.unlink()
    for folder in sorted({item.target.parent for item in staged}):
        _fsync_dir(folder)
