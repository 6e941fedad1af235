"""An SDF file, or a Gazebo model folder (``model.config``), read as libsdformat reads it.

``ign sdf -p`` prints libsdformat's reading (SDF 1.9: includes resolved with the model path set
to the folder's parent, older versions converted).  A file it refuses that the XML still holds
(ragdoll: libsdformat 12 refuses it, Gazebo 11 loads it) is read from its own XML, stated on the
ledger; one that is not well-formed XML, or holds no model, is refused (file:line, exit 2)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.errors import Problem, RobotkitError
from robotkit.urdfxml import MalformedXML, is_element, parse_file, parse_text

ENV_KEYS = ("SDF_PATH", "GAZEBO_MODEL_PATH", "IGN_GAZEBO_RESOURCE_PATH", "GZ_SIM_RESOURCE_PATH")


@dataclass
class Lines:
    """A file's text, searched for an element's line (``file:line`` on the ledger)."""

    path: Path
    lines: list[str]

    def where(self, kind: str, name: str | None, link: str | None = None) -> str:
        """``file:line`` of the element ``<kind name="name">`` (inside link ``link`` when given);
        the file alone when it is not there."""
        start = self.find("link", link) if link else 1
        line = self.find(kind, name, start or 1) if name else self.tag_line(kind, start or 1)
        return f"{self.path}:{line}" if line else str(self.path)

    def find(self, kind: str, name: str, start: int = 1) -> int | None:
        """The line of ``<kind name="name">``; a nested model's ``model/name`` (its ``model::name``)
        inside ``<model name="model">`` when no element has the whole name (iris's link
        'iris/imu_link' is one name); None when it is not in the file."""
        line = self.line_of(kind, name, start)
        parts = name.split("/")
        if line is not None or len(parts) == 1:
            return line
        for model in parts[:-1]:
            start = self.line_of("model", model, start)
            if start is None:
                return None
        return self.line_of(kind, parts[-1], start)

    def tag_line(self, kind: str, start: int = 1) -> int | None:
        """The line of the first ``<kind>`` from ``start`` (an element without a name)."""
        pattern = re.compile(rf"<{kind}[\s/>]")
        return next((i for i, line in enumerate(self.lines[start - 1:], start) if pattern.search(line)), None)

    def line_of(self, kind: str, name: str | None, start: int = 1) -> int | None:
        pattern = re.compile(rf"<{kind}\b[^>]*\bname\s*=\s*[\"']{re.escape(name or '')}[\"']")
        return next((i for i, line in enumerate(self.lines[start - 1:], start) if pattern.search(line)), None)


@dataclass
class Source:
    path: Path
    model: object  # the <model> element (lxml)
    lines: list[str]  # the original file's text, for file:line on the ledger
    via: str  # "libsdformat" | "xml"
    refused: str = ""  # libsdformat's words when it refused the file
    config: dict = field(default_factory=dict)  # model.config: name, version, description, authors
    model_path: Path | None = None
    renamed: dict = field(default_factory=dict)  # new joint name -> the file's
    unknown_scripts: set = field(default_factory=set)  # Gazebo material names without a known colour
    includes: dict = field(default_factory=dict)  # an included model's name ('a/b' nested) -> its Lines
    renamed_as: dict = field(default_factory=lambda: {"link": {}, "joint": {}, "frame": {}})  # new -> the file's

    def original(self, kind: str, name: str | None) -> str | None:
        """The name the file gives the link, joint or frame the import calls ``name``."""
        name = self.renamed_as.get(kind, {}).get(name, name)
        return self.renamed.get(name, name) if kind == "joint" else name

    def where(self, kind: str, name: str | None, link: str | None = None) -> str:
        """``file:line`` of the element ``<kind name="name">`` (inside link ``link`` when given):
        in the original file, or the file of the included model it came from."""
        name, link = self.original(kind, name), self.original("link", link)
        text, key = Lines(self.path, self.lines), link or name or ""
        for prefix in sorted(self.includes, key=len, reverse=True):
            if key.startswith(prefix + "/"):
                text, cut = self.includes[prefix], len(prefix) + 1
                link, name = (link[cut:], name) if link else (None, name[cut:] if name else name)
                break
        return text.where(kind, name, link)

    def where_el(self, kind: str, el) -> str:
        """:meth:`where` of a link's visual or collision ``el``."""
        return self.where(kind, el.get("name"), self.link_of(el))

    def link_of(self, el) -> str:
        """The name, as the model's ('a/b' in a nested model), of the link holding ``el``."""
        link, scope, node = el.getparent(), [], el.getparent().getparent()
        while node is not None and node is not self.model:
            if node.tag == "model":
                scope.insert(0, node.get("name", ""))
            node = node.getparent()
        return "/".join([*scope, link.get("name", "")])


def included(model, model_path: Path | None, scope: str = "", depth: int = 0) -> dict:
    """The models ``model`` (the original's XML) includes from the model path, and those they
    include: their name as the model's ('a/b' nested) -> their file's Lines."""
    out: dict = {}
    for inc in (model.findall("include") if model_path is not None and depth < 8 else ()):
        uri = (inc.findtext("uri") or "").strip()
        try:
            file = locate(model_path / uri[len("model://"):])[0] if uri.startswith("model://") else None
            inner = _model(parse_file(file).getroot()) if file is not None and file.is_file() else None
        except (RobotkitError, MalformedXML):
            continue
        name = (inc.findtext("name") or "").strip() or (inner.get("name", "") if inner is not None else "")
        if inner is None or not name:
            continue
        out[scope + name] = Lines(file.absolute(), file.read_text(encoding="utf-8", errors="replace").splitlines())
        out.update(included(inner, model_path, f"{scope}{name}/", depth + 1))
    for nested in (model.findall("model") if depth < 8 else ()):
        out.update(included(nested, model_path, f"{scope}{nested.get('name', '')}/", depth + 1))
    return out


def locate(path: str | os.PathLike) -> tuple[Path, dict]:
    """(the SDF file, model.config's metadata) of a file or a model folder."""
    p = Path(path)
    if not p.is_dir():
        config = p.parent / "model.config"
        return p, read_config(config)[1] if config.is_file() else {}
    config = p / "model.config"
    if not config.is_file():
        raise RobotkitError(Problem("a model folder without model.config", file=str(p)))
    files, meta = read_config(config)
    for version, name in sorted(files, key=lambda f: _version(f[0]), reverse=True):
        if (not version or _version(version) > (1, 2)) and (p / name).is_file():
            return p / name, meta
    raise RobotkitError(Problem("model.config names no SDF file newer than 1.2 that exists in the folder",
                                file=str(config)))


def _version(text: str) -> tuple[int, ...]:
    return tuple(int(x) for x in re.findall(r"\d+", text or "0")) or (0,)


def read_config(config: Path) -> tuple[list[tuple[str, str]], dict]:
    """([(SDF version, file)], metadata: name, version, description, authors) of a model.config."""
    try:
        root = parse_file(config).getroot()
    except MalformedXML as exc:
        raise RobotkitError(Problem(f"not well-formed XML: {exc}", file=str(config), line=exc.line)) from None
    files = [(el.get("version", ""), (el.text or "").strip()) for el in root.findall("sdf")]
    text = lambda tag: " ".join((root.findtext(tag) or "").split())  # noqa: E731
    authors = [{"name": " ".join((a.findtext("name") or "").split()),
                **({"email": a.findtext("email").strip()} if (a.findtext("email") or "").strip() else {})}
               for a in root.findall("author") if (a.findtext("name") or "").strip()]
    meta = {"name": text("name"), "version": text("version"), "description": text("description"),
            "authors": authors}
    return files, meta


def printed(file: Path, model_path: Path | None) -> subprocess.CompletedProcess:
    """``ign sdf -p FILE`` with ``model_path`` on every model path libsdformat reads."""
    if shutil.which("ign") is None:
        return subprocess.CompletedProcess(["ign"], 127, "", "Error: ign (libsdformat's command) is not installed")
    env = dict(os.environ)
    if model_path is not None:
        for key in ENV_KEYS:
            env[key] = os.pathsep.join(filter(None, [str(model_path), env.get(key, "")]))
    return subprocess.run(["ign", "sdf", "-p", str(Path(file).absolute())], capture_output=True, text=True, env=env)


def read(path: str | os.PathLike) -> Source:
    """The SDF (or model folder) ``path`` through libsdformat; its own XML when libsdformat refuses it."""
    file, config = locate(path)
    if not file.is_file():
        raise RobotkitError(Problem("no such file", file=str(file)))
    original = file.read_text(encoding="utf-8", errors="replace")
    model_path = file.absolute().parent.parent
    result = printed(file, model_path)
    refused = "" if result.returncode == 0 and "<model" in result.stdout else _words(result.stderr)
    try:
        tree = parse_text(result.stdout) if not refused else parse_file(file)
    except MalformedXML as exc:
        raise RobotkitError(Problem(f"not well-formed XML: {exc.expat or exc}", file=str(file),
                                    line=exc.expat_line or exc.line)) from None
    model = _model(tree.getroot())
    if model is None:
        raise RobotkitError(Problem(refused or "holds no <model>", file=str(file)))
    try:
        mine = model if refused else _model(parse_file(file).getroot())
    except MalformedXML:
        mine = None
    return Source(file.absolute(), model, original.splitlines(), "xml" if refused else "libsdformat", refused,
                  config, model_path, includes=included(mine, model_path) if mine is not None else {})


def _model(root):
    if root.tag == "model":
        return root
    found = [el for el in root if is_element(el) and el.tag == "model"]
    if not found:
        found = [el for w in root.findall("world") for el in w.findall("model")]
    return found[0] if found else None


def _words(stderr: str) -> str:
    """libsdformat's first error, on one line."""
    stderr = re.sub(r"\x1b\[[0-9;]*m", "", stderr)
    lines = [ln.strip() for ln in stderr.splitlines() if ln.strip() and "libignition-tools-backward" not in ln]
    errors = [ln for ln in lines if "rror" in ln] or lines
    return " ".join(errors[0].split()) if errors else "libsdformat refused the file"
