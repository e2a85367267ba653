"""Results keyed by content: a recording's result is found again by the hash
of its bytes, its parameter file's bytes and the command, so a rerun skips
what is done (wherever the files moved) and redoes what changed. Every file
is written to a temporary name and renamed into place: a killed run never
leaves a half-written file that a rerun would read back."""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from importlib.metadata import PackageNotFoundError, version

ROWS = Path(".fleet") / "rows"


def _package_version() -> str:
    try:
        return version("hdjoint")
    except PackageNotFoundError:
        return "source"


def file_digest(path: str | os.PathLike | None) -> str:
    h = hashlib.sha256()
    if path is not None:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


def result_key(command: str, recording: str, params: str | None, options: dict) -> str:
    """The hash a result is stored under: command, options, package version
    and the contents (not the names) of the recording and its parameters."""
    h = hashlib.sha256()
    for part in (command, json.dumps(options, sort_keys=True), _package_version(),
                 file_digest(recording), file_digest(params)):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()


def atomic_write(path: str | os.PathLike, data: bytes) -> None:
    """DATA into PATH through a temporary file beside it (never through or over a link: io.outputs)."""
    from hdjoint.io.outputs import open_temp, replace_into
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    f, tmp = open_temp(path, binary=True)
    try:
        with f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)
        replace_into(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def row_path(out: str | os.PathLike, key: str) -> Path:
    return Path(out) / ROWS / f"{key}.json"


def save_row(out: str | os.PathLike, key: str, row: dict) -> None:
    atomic_write(row_path(out, key), (json.dumps(row, default=float) + "\n").encode())


def load_row(out: str | os.PathLike, key: str) -> dict | None:
    """The stored row, or None when there is none (or it is unreadable: then it is redone)."""
    try:
        return json.loads(row_path(out, key).read_text())
    except (OSError, json.JSONDecodeError):
        return None
