"""A shared cache location behind a URL: any filesystem fsspec supports.

``ROBOTKIT_CACHE=s3://bucket/robotkit`` (or ``gs://``, ``az://``, ``sftp://host/path``,
``file:///mnt/shared/robotkit``...) makes the mesh cache a team's and CI's: an entry one
machine computed is read by every other.  :class:`robotkit.mesh.cache.Cache` keeps its
local folder as a read-through copy and uses this module only for the shared copy.

- **Credentials** come from each backend's usual environment and configuration files
  (``AWS_*`` and ``~/.aws`` for S3, ``GOOGLE_APPLICATION_CREDENTIALS`` for GCS, ssh config
  for SFTP) or fsspec's own ``FSSPEC_<PROTOCOL>`` variables; never from recipes.
- **Publication is atomic.**  Object stores (S3, GCS, Azure, memory) make an object
  visible only once it is whole, so entries are written in place; on filesystems with
  renames (local, SFTP, SMB, HDFS) an entry is written under a temporary name and moved.
  Each entry is published payload first, manifest last, and the payload's name carries
  its checksum, so a reader never sees a manifest naming a partial payload and two
  writers of one entry cannot mix their bytes.
- **Reads are verified** by the cache (sizes, checksums, shapes) like local entries.
- ``ROBOTKIT_CACHE_READONLY=1`` reads the shared copy and never writes it (pull-request
  jobs of untrusted forks: give them read-only credentials too).

fsspec and the backend package (s3fs, gcsfs, adlfs, sshfs) are imported only here, only
when a URL is configured; a missing one is named with the package to install.
"""

from __future__ import annotations

import os
import uuid

OBJECT_STORES = {"s3", "s3a", "gs", "gcs", "az", "abfs", "abfss", "adl", "memory", "oss", "r2"}
"""Protocols whose writes appear whole or not at all (no temporary name needed)."""


def is_url(location: str) -> bool:
    """Whether a cache location names a remote filesystem (``scheme://...``), not a folder."""
    head, sep, _ = location.partition("://")
    return bool(sep) and head.isidentifier() and len(head) > 1


def read_only() -> bool:
    """``ROBOTKIT_CACHE_READONLY`` set to anything but empty, 0, false or no."""
    return os.environ.get("ROBOTKIT_CACHE_READONLY", "").strip().lower() not in ("", "0", "false", "no")


class RemoteError(Exception):
    """The shared cache could not be reached or written (costs time, never correctness)."""


class RemoteStore:
    """Bytes under relative names below one fsspec URL."""

    def __init__(self, url: str):
        try:
            from fsspec.core import url_to_fs
        except ImportError:  # pragma: no cover - fsspec is a dependency of robotkit[remote]
            raise RemoteError("ROBOTKIT_CACHE is a URL but fsspec is not installed "
                              "(pip install 'robotkit[remote]')") from None
        self.url = url.rstrip("/")
        try:
            self.fs, self.base = url_to_fs(self.url)
        except (ImportError, ValueError) as exc:
            raise RemoteError(f"cannot open the cache {url}: {exc}") from None
        protocols = self.fs.protocol if isinstance(self.fs.protocol, (tuple, list)) else (self.fs.protocol,)
        self.atomic_put = bool(OBJECT_STORES.intersection(protocols))

    def _path(self, name: str) -> str:
        return f"{self.base.rstrip('/')}/{name}"

    def get(self, name: str) -> bytes | None:
        """The bytes stored under ``name``, or None when there is no such object."""
        try:
            return self.fs.cat_file(self._path(name))
        except FileNotFoundError:
            return None
        except Exception as exc:  # network, permissions, backend errors
            raise RemoteError(f"cannot read {name} from {self.url}: {exc}") from exc

    def exists(self, name: str) -> bool:
        """Whether an object is stored under ``name`` (one HEAD or stat, no listing)."""
        try:
            self.fs.info(self._path(name))
        except FileNotFoundError:
            return False
        except Exception as exc:  # network, permissions, backend errors
            raise RemoteError(f"cannot read {name} from {self.url}: {exc}") from exc
        return True

    def put(self, name: str, data: bytes) -> None:
        """Publish ``data`` under ``name`` so that readers see all of it or nothing."""
        path = self._path(name)
        try:
            parent = path.rsplit("/", 1)[0]
            if not self.atomic_put:
                self.fs.makedirs(parent, exist_ok=True)
            if self.atomic_put:
                self.fs.pipe_file(path, data)
                return
            tmp = f"{parent}/.{name.rsplit('/', 1)[-1]}.{uuid.uuid4().hex}.tmp"
            self.fs.pipe_file(tmp, data)
            try:
                self.fs.mv(tmp, path)
            except Exception:
                try:
                    self.fs.rm_file(tmp)
                except Exception:
                    pass
                raise
        except Exception as exc:
            raise RemoteError(f"cannot write {name} to {self.url}: {exc}") from exc

    def remove(self, name: str) -> None:
        try:
            self.fs.rm_file(self._path(name))
        except Exception:
            pass
