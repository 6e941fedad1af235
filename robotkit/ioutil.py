"""Small file helpers shared by every stage: atomic, change-only writes."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def write_if_changed(path: str | os.PathLike, data: bytes | str) -> bool:
    """Write ``data`` to ``path`` atomically; leave the file untouched if equal.

    Returns True when the file was (re)written.  A reader never sees a half
    written file: data goes to a temporary file in the same folder first.
    """
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    try:
        if path.stat().st_size == len(data) and path.read_bytes() == data:
            return False
    except FileNotFoundError:
        pass
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return True
