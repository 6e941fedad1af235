"""A content-addressed disk cache for expensive mesh results (CoACD, hulls, decimation).

**Key.**  sha256 over canonical JSON of: the cache format version, the
operation name, the effective parameters, the versions of the libraries that
can change a result (trimesh, coacd, meshlib and meshoptimizer (decimation),
manifold3d, numpy, scipy) and robotkit's version, followed by the digest of every input (raw
bytes, or :func:`mesh_digest` of a mesh).  Changing any of them is a miss.

**Location.**  ``Cache(root)``; by default ``$ROBOTKIT_CACHE``, else
``$XDG_CACHE_HOME/robotkit``, else ``~/.cache/robotkit``.  When ``$ROBOTKIT_CACHE`` (or
``root``) is a URL of a filesystem fsspec supports (``s3://bucket/prefix``...), that is a
*shared* cache (:mod:`robotkit.mesh.remote`) and the local default folder is its
read-through copy: a lookup tries the local copy, then the shared one (verified, then
copied locally); a computed entry is stored locally and published to the shared copy
unless ``ROBOTKIT_CACHE_READONLY`` is set, and so is an entry found in the local copy that
the shared one lacks (made before the team shared its cache: checked once per key and
process, by one existence check, never by listing the shared copy).  Entries live in
``<root>/v1/<key[:2]>/`` (the same names locally and remotely):

- ``<key>.<payload sha256[:16]>.bin``: the meshes, as little-endian float64
  vertices and int32/int64 faces back to back (exact: binary STL would round
  to float32; ``.npz`` embeds zip timestamps);
- ``<key>.json``: the manifest: key, operation, parameters, versions, mesh
  shapes, the payload's file name, size and sha256, and an optional JSON
  ``info`` dict (a report stored with the meshes).

**Writes are atomic**: each file is written to a temporary file in the same
folder and moved into place with ``os.replace``; the payload first, the
manifest last, so a manifest only ever names a complete payload, and the
payload's name carries its checksum, so two writers never replace each
other's payload with different bytes.  Writes are not flushed to the disk
(``fsync``: a quarter of a second per imported model's verification on a busy
disk): a file a crash left empty or short fails the checks below and is
recomputed.  **Reads verify**: an entry whose
manifest is unreadable or names another key, whose payload is missing, of the
wrong size or checksum, or does not parse into valid meshes is removed and
recomputed, never used.  **Concurrency**: ``get_or_compute`` holds an
exclusive ``fcntl`` lock on ``<key>.lock`` while it looks up, computes and
stores, so two processes asking for the same key compute it once (the second
waits, then hits).  Where ``fcntl`` is missing (Windows) both compute, and
the atomic writes still keep the entry whole.

Values are a ``trimesh.Trimesh``, a list of them, or a ``(mesh or list,
info dict)`` tuple; or :class:`Files` (named byte strings: a task's output files, stored
back to back in the payload, their names and sizes in the manifest).  A miss returns the value rebuilt from the stored arrays
(``process=False``), so a miss and a later hit return identical arrays.
Meshes are stored as geometry only (no visual data).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np

import robotkit
from robotkit.mesh.remote import RemoteError, RemoteStore, is_url, read_only

CACHE_FORMAT = 1
REPORT_ENV = "ROBOTKIT_CACHE_REPORT"
LIBRARIES = ("trimesh", "coacd", "meshlib", "meshoptimizer", "manifold3d", "numpy", "scipy")


def default_root() -> Path:
    """The local cache folder: ``$ROBOTKIT_CACHE`` when it is a folder, else (no cache set, or
    a shared one named by URL) ``$ROBOTKIT_CACHE_LOCAL``, ``$XDG_CACHE_HOME/robotkit`` or
    ``~/.cache/robotkit``."""
    env = os.environ.get("ROBOTKIT_CACHE")
    if env and not is_url(env):
        return Path(env).expanduser()
    local = os.environ.get("ROBOTKIT_CACHE_LOCAL")
    if local:
        return Path(local).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg and os.path.isabs(os.path.expanduser(xdg)) else Path.home() / ".cache"
    return base / "robotkit"


def library_versions(names: tuple[str, ...] = LIBRARIES) -> dict:
    """Installed versions of the libraries that shape cached results, plus robotkit's (looked
    up once per process: the installed packages do not change under a running build)."""
    return dict(_versions(tuple(names)))


@functools.lru_cache(maxsize=None)
def _versions(names: tuple[str, ...]) -> tuple:
    from importlib import metadata

    out = {}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    out["robotkit"] = robotkit.__version__
    return tuple(out.items())


def mesh_digest(mesh) -> str:
    """sha256 (hex) of a mesh's geometry: float64 vertices and int64 faces, little-endian, with shapes."""
    V = np.ascontiguousarray(np.asarray(mesh.vertices, dtype="<f8") + 0.0)  # -0.0 -> 0.0
    F = np.ascontiguousarray(np.asarray(mesh.faces, dtype="<i8"))
    h = hashlib.sha256()
    h.update(f"mesh {V.shape[0]} {F.shape[0]}\n".encode())
    h.update(V.tobytes())
    h.update(F.tobytes())
    return h.hexdigest()


@functools.lru_cache(maxsize=None)
def code_digest() -> str:
    """sha256 of robotkit's own files (code, presets, templates shipped in the package): a result
    cached by an earlier robotkit (a build task's, a check stage's) is never reused by another."""
    root = Path(robotkit.__file__).resolve().parent
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def canonical_json(value) -> str:
    """Deterministic JSON: sorted keys, no spaces, numpy values and tuples as plain JSON, no NaN."""
    return json.dumps(plain(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


def plain(value):
    """A JSON-able copy: numpy numbers and arrays, tuples to plain Python (no -0.0)."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) + 0.0
    if value is None or isinstance(value, str):
        return value
    raise TypeError(f"cannot put a {type(value).__name__} into a cache key or manifest")


_SHARED: set = set()
"""(shared cache URL, key) of the entries this process knows the shared copy holds."""


class Files(dict):
    """A cached value made of files: relative path (str) -> content (bytes)."""


class CacheCorrupt(Exception):
    """An entry failed verification (internal: the entry is removed and recomputed)."""


class Cache:
    """See the module docstring.  ``versions`` overrides :func:`library_versions` (tests)."""

    def __init__(self, root: str | os.PathLike | None = None, versions: dict | None = None, *,
                 local: str | os.PathLike | None = None, run: Callable[[Callable[[], object]], object] | None = None):
        """``run(compute)`` computes a miss (the pipeline passes one that sends it to a Dask
        cluster when one is configured); by default here, in this process."""
        self.run = run or (lambda compute: compute())
        location = os.fspath(root) if root is not None else os.environ.get("ROBOTKIT_CACHE", "")
        self.remote, self.remote_writable, self.remote_problems = None, False, []
        self.stats = {"hits": 0, "misses": 0, "corrupt": 0, "stored": 0,
                      "remote_hits": 0, "remote_corrupt": 0, "published": 0, "remote_errors": 0}
        if location and is_url(location):
            try:
                self.remote = RemoteStore(location)
                self.remote_writable = not read_only()
            except RemoteError as exc:
                self._remote_problem(exc)
            self.root = Path(local).expanduser() if local is not None else default_root()
        else:
            self.root = Path(location).expanduser() if location else default_root()
        self.versions = dict(versions) if versions is not None else library_versions()

    # --- keys and paths ----------------------------------------------------------------------

    def key(self, op: str, params: dict, inputs) -> str:
        """The entry key for ``op`` with ``params`` on ``inputs`` (bytes, str, mesh, or a list of those)."""
        head = canonical_json({"format": CACHE_FORMAT, "op": op, "params": params, "versions": self.versions})
        h = hashlib.sha256(head.encode())
        for item in (inputs if isinstance(inputs, (list, tuple)) else [inputs]):
            h.update(b"\0" + _input_digest(item).encode())
        return h.hexdigest()

    def folder(self, key: str) -> Path:
        return self.root / f"v{CACHE_FORMAT}" / key[:2]

    def manifest_path(self, key: str) -> Path:
        return self.folder(key) / f"{key}.json"

    @staticmethod
    def entry_name(key: str, file: str) -> str:
        """The name of one of an entry's files relative to a cache root."""
        return f"v{CACHE_FORMAT}/{key[:2]}/{file}"

    # --- public API ---------------------------------------------------------------------------

    def get_or_compute(self, op: str, params: dict, inputs, compute: Callable[[], object], *,
                       lock: bool = True):
        """The cached value for (op, params, inputs), computing and storing it on a miss."""
        key = self.key(op, params, inputs)
        with (self._locked(key) if lock else contextlib.nullcontext()):
            value = self.get(key)
            if value is not None:
                return value
            self.stats["misses"] += 1
            return self.put(key, self.run(compute), op=op, params=params)

    def get(self, key: str):
        """The verified value stored under ``key``, or None (a corrupt entry is removed)."""
        path = self.manifest_path(key)
        if not path.exists():
            return self._get_remote(key) if self.remote is not None else None
        try:
            value = self._read(key, path)
        except CacheCorrupt:
            self.stats["corrupt"] += 1
            self._remove(key)
            return self._get_remote(key) if self.remote is not None else None
        self.stats["hits"] += 1
        if self.remote is not None and self.remote_writable:
            self._share(key, path)
        return value

    def _share(self, key: str, path: Path) -> None:
        """Publish a local entry the shared copy lacks (one made before the team shared its
        cache, or while the shared copy was unreachable).  One existence check per key and
        process; a key found there, or published, is not checked again."""
        name = self.entry_name(key, f"{key}.json")
        if (self.remote.url, key) in _SHARED:
            return
        try:
            if not self.remote.exists(name):
                manifest_bytes = path.read_bytes()
                payload_file = json.loads(manifest_bytes)["payload"]["file"]
                payload = (self.folder(key) / payload_file).read_bytes()
                if not self._publish(key, payload_file, payload, manifest_bytes):
                    return
        except RemoteError as exc:
            self._remote_problem(exc)
            return
        except (OSError, ValueError, KeyError, TypeError):
            return  # the local entry changed under us: it was just read and verified
        _SHARED.add((self.remote.url, key))

    def _get_remote(self, key: str):
        """The shared copy's entry, verified and copied into the local folder; None on a miss,
        a corrupt entry (republished by the next put) or an unreachable cache."""
        try:
            manifest_bytes = self.remote.get(self.entry_name(key, f"{key}.json"))
            if manifest_bytes is None:
                return None
            payloads = {}

            def payload(file: str) -> bytes:
                data = self.remote.get(self.entry_name(key, file))
                if data is None:
                    raise CacheCorrupt("payload missing")
                payloads[file] = data
                return data

            try:
                value = self._decode(key, manifest_bytes, payload)
            except CacheCorrupt:
                self.stats["remote_corrupt"] += 1
                return None
        except RemoteError as exc:
            self._remote_problem(exc)
            return None
        try:
            folder = self.folder(key)
            folder.mkdir(parents=True, exist_ok=True)
            for file, data in payloads.items():
                _atomic_write(folder / file, data)
            _atomic_write(self.manifest_path(key), manifest_bytes)
        except OSError:
            pass
        self.stats["remote_hits"] += 1
        _SHARED.add((self.remote.url, key))
        return value

    def _remote_problem(self, exc) -> None:
        """Note that the shared copy failed; the first failure of a process is told once: to the
        file named by ``$ROBOTKIT_CACHE_REPORT`` (the CLI prints it after the build: task output is
        captured), else on stderr."""
        self.stats["remote_errors"] += 1
        if not self.remote_problems:
            line = f"robotkit: warning: shared cache: {exc} (building without it)"
            report = os.environ.get(REPORT_ENV)
            try:
                if not report:
                    raise OSError
                with open(report, "a", encoding="utf-8") as f:
                    f.write(line.replace("\n", " ") + "\n")
            except OSError:
                import sys

                print(line, file=sys.stderr)
        self.remote_problems.append(str(exc))

    def put(self, key: str, value, *, op: str = "", params: dict | None = None):
        """Store ``value`` under ``key``; return it rebuilt from the stored arrays."""
        if isinstance(value, Files):
            names = sorted(value)
            payload = b"".join(bytes(value[n]) for n in names)
            shapes = [{"file": n, "size": len(value[n])} for n in names]
            return self._store(key, "files", shapes, payload, None, op, params)
        meshes, kind, info = _unpack(value)
        blobs, shapes = [], []
        for m in meshes:
            V = np.ascontiguousarray(np.asarray(m.vertices, dtype="<f8").reshape(-1, 3))
            F = np.asarray(m.faces, dtype=np.int64).reshape(-1, 3)
            ftype = "<i4" if F.size == 0 or F.max() < 2 ** 31 - 1 else "<i8"
            F = np.ascontiguousarray(F.astype(ftype))
            blobs += [V.tobytes(), F.tobytes()]
            shapes.append({"vertices": int(V.shape[0]), "faces": int(F.shape[0]), "faces_dtype": ftype})
        return self._store(key, kind, shapes, b"".join(blobs), info, op, params)

    def _store(self, key: str, kind: str, shapes: list, payload: bytes, info, op: str, params: dict | None):
        digest = hashlib.sha256(payload).hexdigest()
        manifest = {
            "format": CACHE_FORMAT, "key": key, "op": op, "params": plain(params or {}),
            "versions": self.versions, "kind": kind, "meshes": shapes, "info": plain(info),
            "payload": {"file": f"{key}.{digest[:16]}.bin", "size": len(payload), "sha256": digest},
        }
        rebuilt = _value(kind, payload, shapes, manifest["info"])
        manifest_bytes = (json.dumps(manifest, sort_keys=True, indent=1) + "\n").encode()
        try:
            folder = self.folder(key)
            folder.mkdir(parents=True, exist_ok=True)
            _atomic_write(folder / manifest["payload"]["file"], payload)
            _atomic_write(self.manifest_path(key), manifest_bytes)
            self.stats["stored"] += 1
        except OSError:
            pass  # a read-only or full cache folder costs time, never correctness
        if self.remote is not None and self.remote_writable:
            self._publish(key, manifest["payload"]["file"], payload, manifest_bytes)
        return rebuilt

    def _publish(self, key: str, payload_file: str, payload: bytes, manifest_bytes: bytes) -> bool:
        """Payload first, manifest last: a reader never finds a manifest without its payload.
        Whether the entry was published."""
        try:
            self.remote.put(self.entry_name(key, payload_file), payload)
            self.remote.put(self.entry_name(key, f"{key}.json"), manifest_bytes)
        except RemoteError as exc:
            self._remote_problem(exc)
            return False
        self.stats["published"] += 1
        _SHARED.add((self.remote.url, key))
        return True

    def clear(self) -> None:
        """Remove every entry of this cache format."""
        import shutil

        shutil.rmtree(self.root / f"v{CACHE_FORMAT}", ignore_errors=True)

    # --- internals ----------------------------------------------------------------------------

    def _read(self, key: str, path: Path):
        try:
            manifest_bytes = path.read_bytes()
        except OSError as exc:
            raise CacheCorrupt(str(exc)) from exc
        return self._decode(key, manifest_bytes, lambda file: (self.folder(key) / file).read_bytes())

    @staticmethod
    def _decode(key: str, manifest_bytes: bytes, read_payload: Callable[[str], bytes]):
        """The value of one entry from its manifest and a reader of its payload, verified."""
        try:
            manifest = json.loads(manifest_bytes.decode("utf-8"))
            if manifest.get("format") != CACHE_FORMAT or manifest.get("key") != key:
                raise CacheCorrupt("manifest of another key or format")
            pay = manifest["payload"]
            if os.path.basename(pay["file"]) != pay["file"] or not pay["file"].startswith(f"{key}."):
                raise CacheCorrupt("payload name with a folder or of another key")
            data = read_payload(pay["file"])
            if len(data) != pay["size"] or hashlib.sha256(data).hexdigest() != pay["sha256"]:
                raise CacheCorrupt("payload size or checksum mismatch")
            return _value(manifest["kind"], data, manifest["meshes"], manifest.get("info"))
        except CacheCorrupt:
            raise
        except (OSError, ValueError, KeyError, TypeError, AttributeError, UnicodeDecodeError) as exc:
            raise CacheCorrupt(str(exc)) from exc

    def _remove(self, key: str) -> None:
        folder = self.folder(key)
        with contextlib.suppress(OSError):
            self.manifest_path(key).unlink()
        with contextlib.suppress(OSError):
            for p in folder.glob(f"{key}.*.bin"):
                p.unlink()

    @contextlib.contextmanager
    def _locked(self, key: str):
        try:
            import fcntl
        except ImportError:  # Windows: no lock, atomic writes only
            yield
            return
        try:
            folder = self.folder(key)
            folder.mkdir(parents=True, exist_ok=True)
            fd = os.open(folder / f"{key}.lock", os.O_RDWR | os.O_CREAT, 0o644)
        except OSError:
            yield
            return
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            with contextlib.suppress(OSError):
                fcntl.flock(fd, fcntl.LOCK_UN)
            os.close(fd)


def _input_digest(item) -> str:
    if isinstance(item, (bytes, bytearray, memoryview)):
        return "bytes:" + hashlib.sha256(bytes(item)).hexdigest()
    if isinstance(item, str):
        return "str:" + hashlib.sha256(item.encode()).hexdigest()
    if hasattr(item, "vertices") and hasattr(item, "faces"):
        return "mesh:" + mesh_digest(item)
    raise TypeError(f"cache inputs must be bytes, str or meshes, not {type(item).__name__}")


def _value(kind: str, payload: bytes, shapes: list, info):
    """An entry's value from its payload and the shapes its manifest lists."""
    if kind != "files":
        return _build(kind, _parse(payload, shapes), info)
    out, at = Files(), 0
    for s in shapes:
        name, size = s["file"], int(s["size"])
        if not isinstance(name, str) or name.startswith("/") or ".." in name.split("/") or not 0 <= size <= len(payload) - at:
            raise CacheCorrupt("bad file in a files entry")
        out[name] = payload[at:at + size]
        at += size
    if at != len(payload):
        raise CacheCorrupt("payload longer than its manifest")
    return out


def _unpack(value):
    import trimesh

    info = None
    if isinstance(value, tuple):
        if len(value) != 2 or not isinstance(value[1], dict):
            raise TypeError("a cached tuple must be (mesh or list of meshes, info dict)")
        value, info = value
    if isinstance(value, trimesh.Trimesh):
        return [value], "mesh", info
    if isinstance(value, list) and all(isinstance(m, trimesh.Trimesh) for m in value):
        return value, "meshes", info
    raise TypeError("a cached value must be a trimesh.Trimesh, a list of them, or (that, info dict)")


def _parse(data: bytes, shapes: list) -> list:
    import trimesh

    out, at = [], 0
    for s in shapes:
        nv, nf, ftype = int(s["vertices"]), int(s["faces"]), s["faces_dtype"]
        if ftype not in ("<i4", "<i8") or nv < 0 or nf < 0:
            raise CacheCorrupt("bad mesh shape")
        vb, fb = nv * 24, nf * 3 * np.dtype(ftype).itemsize
        if at + vb + fb > len(data):
            raise CacheCorrupt("payload shorter than its manifest")
        V = np.frombuffer(data, dtype="<f8", count=nv * 3, offset=at).reshape(nv, 3).astype(np.float64)
        F = np.frombuffer(data, dtype=ftype, count=nf * 3, offset=at + vb).reshape(nf, 3).astype(np.int64)
        at += vb + fb
        if nf and (F.min() < 0 or F.max() >= nv):
            raise CacheCorrupt("face index out of range")
        out.append(trimesh.Trimesh(V, F, process=False))
    if at != len(data):
        raise CacheCorrupt("payload longer than its manifest")
    return out


def _build(kind: str, meshes: list, info):
    if kind == "mesh":
        if len(meshes) != 1:
            raise CacheCorrupt("a single-mesh entry holds several meshes")
        value = meshes[0]
    elif kind == "meshes":
        value = meshes
    else:
        raise CacheCorrupt(f"unknown kind {kind!r}")
    return (value, info) if info is not None else value


def _atomic_write(path: Path, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:  # not fsync'd: a file a crash cuts short fails the reads' checks
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
