"""An MJCF and every file it names, read by this project with bounds, before MuJoCo sees it.

MuJoCo opens the files an MJCF names (``<include file>``, meshes, textures, height fields,
skins) on its own, with no size limit and wherever the path leads. Here the project reads them
instead (:func:`read_mjcf`), and MuJoCo compiles the result from memory
(``mujoco.MjSpec.from_string(xml, assets=...)``), so it never opens a path that was not
checked:

- every file is read with :func:`evomotion.textio.read_file_bytes` (a FIFO, a device or a
  folder is refused without blocking), an MJCF file at most :data:`MAX_XML_BYTES`, all MJCF
  text together at most :data:`MAX_XML_TOTAL`, an asset at most :data:`MAX_ASSET_BYTES`, all
  assets :data:`MAX_ASSETS_TOTAL`, at most :data:`MAX_FILES` files;
- every path stays inside the root folder (the spec's folder, or the package of an
  ``evomotion:``/``dm_control:`` MJCF): no absolute path, no ``..``, no symbolic link that
  leads outside;
- ``<include file=...>`` is expanded here (the file's ``<mujoco>`` children replace the
  element; a path relative to the including file's folder, else to the main MJCF's, as
  MuJoCo looks), at most :data:`MAX_INCLUDE_DEPTH` deep; a file that includes itself (a cycle)
  or is included twice (MuJoCo includes a file once) is refused, naming the chain;
- ``<!DOCTYPE>`` and ``<!ENTITY>`` declarations are refused (no entity expansion), elements
  nest at most :data:`MAX_XML_DEPTH` deep, at most :data:`MAX_ELEMENTS` elements (those inside
  ``<replicate>`` counted as often as they are copied);
- what makes MuJoCo allocate far more than the text's size is bounded before it compiles:
  ``<replicate count>`` (product :data:`MAX_REPLICATE`), ``<composite>``/``<flexcomp>``
  ``count`` (:data:`MAX_GRID`), builtin texture and height field sizes and the pixels of a
  PNG texture or height field (:data:`MAX_PIXELS`), ``<size>`` counts (:data:`SIZE_ATTRS`);
- a number that is ``nan``/``inf`` or larger than :data:`MAX_NUMBER` in any attribute is
  refused with the file and line (MuJoCo would only warn and simulate NaN).

Asset files are renamed in the expanded text to unique in-memory names (``meshdir``,
``texturedir`` and ``assetdir`` are applied here and removed). Every failure is one
:class:`~evomotion.errors.FileFormatError` ``FILE:LINE: ...``.
"""

from __future__ import annotations

import hashlib
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from xml.parsers import expat

from evomotion.errors import FileFormatError
from evomotion.textio import read_file_bytes

MAX_XML_BYTES = 8 * 2**20
MAX_XML_TOTAL = 16 * 2**20
MAX_ASSET_BYTES = 32 * 2**20
MAX_ASSETS_TOTAL = 64 * 2**20
MAX_FILES = 256
MAX_INCLUDE_DEPTH = 8
MAX_XML_DEPTH = 128
MAX_ELEMENTS = 50_000
MAX_REPLICATE = 1000
MAX_GRID = 10_000
MAX_PIXELS = 2048 * 2048
#: ``<size>`` attributes MuJoCo allocates by when it compiles or makes data (per element for
#: ``nuser_*``); ``memory`` (the data arena) is bounded after compiling (:mod:`.limits`)
SIZE_ATTRS = {"nuserdata": 1_000_000, "nkey": 1000, "nconmax": 100_000, "njmax": 100_000,
              "nstack": 10_000_000, "nuser_body": 100, "nuser_jnt": 100, "nuser_geom": 100,
              "nuser_site": 100, "nuser_cam": 100, "nuser_tendon": 100,
              "nuser_actuator": 100, "nuser_sensor": 100}
MAX_NUMBER = 1e12

#: attributes that hold names or keywords, not numbers (the rest are checked for nan/inf)
_NAME_ATTRS = frozenset((
    "name", "class", "childclass", "prefix", "joint", "joint1", "joint2", "body", "body1",
    "body2", "site", "site1", "site2", "geom", "geom1", "geom2", "mesh", "material", "texture",
    "hfield", "tendon", "tendon1", "tendon2", "actuator", "target", "objname", "refname",
    "cranksite", "slidersite", "jointinparent", "camera", "flex", "skin", "plugin", "instance",
    "key", "value", "content_type", "model", "light", "sensor", "modelname", "meshdir",
    "texturedir", "assetdir", "bodyname", "objtype", "reftype", "user", "mode", "type",
))
_ASSET_DIRS = {"mesh": "meshdir", "hfield": "meshdir", "skin": "meshdir",
               "texture": "texturedir"}
_BAD_TOKEN = re.compile(r"^[+-]?(nan|inf|infinity)$", re.IGNORECASE)
_PNG = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class MjcfBundle:
    """An MJCF read by :func:`read_mjcf`: the expanded ``xml`` (includes inlined, asset files
    renamed to the keys of ``assets``), the main file ``path``, the SHA-256 of its bytes and
    every file read (``files``)."""

    xml: str
    assets: dict[str, bytes] = field(repr=False)
    path: Path
    sha256: str
    files: tuple[Path, ...]
    #: ``(file, line)`` in the source of each line of ``xml`` (one element per line)
    sources: tuple[tuple[Path, int], ...] = field(default=(), repr=False)

    def locate(self, message: str) -> str:
        """``message`` (MuJoCo's) with its ``line N`` of ``xml`` given as ``FILE:LINE``."""
        def repl(m: re.Match) -> str:
            n = int(m.group(1))
            if 1 <= n <= len(self.sources) and self.sources[n - 1][1]:
                path, line = self.sources[n - 1]
                return f"at {path}:{line}"
            return m.group(0)

        return re.sub(r"\bline (\d+)", repl, message)


class _Reader:
    """The state of one :func:`read_mjcf`: files read, sizes so far, source lines."""

    def __init__(self, main: Path, root: Path) -> None:
        self.main, self.root = main, root
        self.lines: dict[int, tuple[Path, int]] = {}
        self.keep: list[ET.Element] = []  # elements alive, so their ids stay theirs
        self.seen: set[Path] = set()  # the real paths of the MJCF files read
        self.xml_bytes = 0
        self.asset_bytes = 0
        self.assets: dict[str, bytes] = {}
        self.asset_keys: dict[Path, str] = {}
        self.files: list[Path] = []
        self.main_bytes = b""

    # -- errors and paths --------------------------------------------------------------

    def where(self, el: ET.Element) -> tuple[Path, int]:
        return self.lines.get(id(el), (self.main, 0))

    def bad(self, el: ET.Element | None, message: str) -> FileFormatError:
        path, line = self.where(el) if el is not None else (self.main, 0)
        return FileFormatError(path, line or None, message)

    def inside(self, ref: str, base: Path, el: ET.Element | None, what: str) -> Path:
        """The real path of ``ref`` (relative to ``base``) when it lies inside the root."""
        try:
            return confined(ref, base, self.root)
        except ValueError as e:
            raise self.bad(el, f"{what} {ref[:80]!r}: {e}") from None

    def read(self, real: Path, what: str, limit: int, total: int, el) -> bytes:
        """The bytes of ``real``: at most ``limit`` (what is left of ``total``)."""
        if len(self.files) >= MAX_FILES:
            raise self.bad(el, f"expected at most {MAX_FILES} files in the model")
        if limit < min(MAX_XML_BYTES, MAX_ASSET_BYTES):
            shown = f"{total / 2**20:g} MiB" if total >= 2**20 else f"{total} bytes"
            what = f"{what} (all {what}s together at most {shown})"
        data = read_file_bytes(real, what, max(limit, 0))
        self.files.append(real)
        return data

    # -- parsing -----------------------------------------------------------------------

    def parse(self, data: bytes, path: Path) -> ET.Element:
        """The root element of ``data`` (line numbers kept); no DTD, bounded nesting."""
        parser = expat.ParserCreate()
        stack: list[ET.Element] = []
        top: list[ET.Element] = []

        def start(tag: str, attrs: dict[str, str]) -> None:
            if len(stack) >= MAX_XML_DEPTH:
                raise FileFormatError(path, parser.CurrentLineNumber, f"expected elements "
                                      f"nested at most {MAX_XML_DEPTH} deep")
            el = ET.Element(tag, attrs)
            (stack[-1].append if stack else top.append)(el)
            stack.append(el)
            self.keep.append(el)
            self.lines[id(el)] = (path, parser.CurrentLineNumber)

        def end(tag: str) -> None:
            stack.pop()

        def declaration(*args) -> None:
            raise FileFormatError(path, parser.CurrentLineNumber, "expected MJCF without "
                                  "<!DOCTYPE> or <!ENTITY> declarations (no entity expansion)")

        parser.StartElementHandler = start
        parser.EndElementHandler = end
        parser.StartDoctypeDeclHandler = declaration
        parser.EntityDeclHandler = declaration
        parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
        try:
            parser.Parse(data, True)
        except expat.ExpatError as e:
            raise FileFormatError(path, e.lineno, f"column {e.offset + 1}: expected XML "
                                  f"({expat.ErrorString(e.code)})") from None
        except RecursionError:
            raise FileFormatError(path, None, "expected XML (nested too deep)") from None
        if not top or top[0].tag != "mujoco":
            raise FileFormatError(path, 1, "expected an MJCF file: a <mujoco> root element")
        return top[0]

    def load(self, real: Path, shown: Path, el) -> ET.Element:
        left = MAX_XML_TOTAL - self.xml_bytes
        data = self.read(real, "MJCF file", min(MAX_XML_BYTES, left), MAX_XML_TOTAL, el)
        self.xml_bytes += len(data)
        if not self.main_bytes:
            self.main_bytes = data
        return self.parse(data, shown)

    # -- includes ----------------------------------------------------------------------

    def expand(self, el: ET.Element, folder: Path, chain: tuple[Path, ...],
               depth: int = 1) -> None:
        """Replace every ``<include>`` below ``el`` (at ``depth``) by the included file's
        children."""
        i = 0
        while i < len(el):
            child = el[i]
            if child.tag != "include":
                if depth >= MAX_XML_DEPTH:
                    raise self.bad(child, f"expected elements nested at most {MAX_XML_DEPTH} "
                                          "deep (with the included files)")
                self.expand(child, folder, chain, depth + 1)
                i += 1
                continue
            ref = child.get("file", "")
            real = self.inside(ref, folder, child, "<include file>")
            if not real.exists() and folder != self.main.parent:
                real = self.inside(ref, self.main.parent, child, "<include file>")
            if real in chain:
                names = " -> ".join(p.name for p in (*chain[chain.index(real):], real))
                raise self.bad(child, f"<include file={ref[:80]!r}>: the file includes itself "
                                      f"({names})")
            if real in self.seen:
                raise self.bad(child, f"<include file={ref[:80]!r}>: already included (MuJoCo "
                                      "includes a file once)")
            if len(chain) > MAX_INCLUDE_DEPTH:
                raise self.bad(child, f"<include file={ref[:80]!r}>: expected includes nested "
                                      f"at most {MAX_INCLUDE_DEPTH} deep")
            self.seen.add(real)
            sub = self.load(real, real, child)
            self.expand(sub, real.parent, (*chain, real), depth)
            del el[i]
            for k, grand in enumerate(list(sub)):
                el.insert(i + k, grand)
            i += len(sub)

    # -- the expanded tree ---------------------------------------------------------------

    def dirs(self, tree: ET.Element) -> dict[str, str]:
        """``meshdir``/``texturedir`` (``assetdir`` filling in), removed from the tree."""
        found: dict[str, str] = {}
        for comp in tree.iter("compiler"):
            for key in ("assetdir", "meshdir", "texturedir"):
                if key in comp.attrib:
                    value = comp.attrib.pop(key)
                    if value:
                        self.inside(value.rstrip("/") or ".", self.main.parent, comp,
                                    f"<compiler {key}>")
                    found[key] = value
        asset = found.get("assetdir", "")
        return {"meshdir": found.get("meshdir", asset), "texturedir": found.get("texturedir",
                                                                                 asset)}

    def check(self, tree: ET.Element) -> None:
        """Element count and depth, amplifying attributes, numbers, asset files."""
        dirs = self.dirs(tree)
        count = 0
        stack = [(tree, 1, 1)]
        while stack:
            el, depth, copies = stack.pop()
            count += copies
            if count > MAX_ELEMENTS:
                raise self.bad(el, f"expected at most {MAX_ELEMENTS} elements in the model "
                                   "(replicated ones counted as copied)")
            if depth > MAX_XML_DEPTH:
                raise self.bad(el, f"expected elements nested at most {MAX_XML_DEPTH} deep "
                                   "(with the included files)")
            self.numbers(el)
            if el.tag == "replicate":
                copies *= self.product(el, "count", MAX_REPLICATE, "copies (nested "
                                       "<replicate> multiply)", copies)
            elif el.tag in ("composite", "flexcomp"):
                self.product(el, "count", MAX_GRID, "elements")
            elif el.tag == "size":
                for key, limit in SIZE_ATTRS.items():
                    if key in el.attrib:
                        self.product(el, key, limit, key)
            elif el.tag in ("texture", "hfield"):
                self.product(el, ("width", "height") if el.tag == "texture"
                             else ("nrow", "ncol"), MAX_PIXELS, "pixels")
            files = [k for k in el.attrib if k.startswith("file")]
            if files:
                self.asset(el, files, dirs)
            stack.extend((c, depth + 1, copies) for c in el)

    def numbers(self, el: ET.Element) -> None:
        for key, value in el.attrib.items():
            if key in _NAME_ATTRS or key.startswith("file") or (el.tag == "text"
                                                                and key == "data"):
                continue
            for token in value.split():
                bad = _BAD_TOKEN.match(token) is not None
                if not bad and token[:1] in "+-.0123456789" and ("e" in token or "E" in token
                                                                  or len(token) > 12):
                    try:
                        bad = abs(float(token)) > MAX_NUMBER
                    except ValueError:
                        bad = False
                if bad:
                    raise self.bad(el, f"<{el.tag} {key}>: expected finite numbers of at most "
                                       f"{MAX_NUMBER:g} in size, got {token[:40]!r}")

    def product(self, el: ET.Element, keys, limit: int, what: str, factor: int = 1) -> int:
        keys = (keys,) if isinstance(keys, str) else keys
        total = 1
        for key in keys:
            for token in el.get(key, "").split():
                try:
                    n = int(float(token)) if len(token) < 30 else limit + 1
                except (ValueError, OverflowError):
                    continue  # MuJoCo reports it
                total *= max(n, 1)
        if total * factor > limit:
            raise self.bad(el, f"<{el.tag} {' '.join(keys)}>: expected at most {limit} "
                               f"{what}, got {total * factor}")
        return total

    def asset(self, el: ET.Element, keys: list[str], dirs: dict[str, str]) -> None:
        dir_key = _ASSET_DIRS.get(el.tag)
        if dir_key is None:
            raise self.bad(el, f"<{el.tag} {keys[0]}>: files named by <{el.tag}> are not "
                               "supported (inline that model into the MJCF)")
        base = self.main.parent / dirs[dir_key] if dirs[dir_key] else self.main.parent
        for key in keys:
            ref = el.get(key, "")
            real = self.inside(ref, base, el, f"<{el.tag} {key}>")
            if real not in self.asset_keys:
                left = MAX_ASSETS_TOTAL - self.asset_bytes
                data = self.read(real, f"{el.tag} file", min(MAX_ASSET_BYTES, left),
                                 MAX_ASSETS_TOTAL, el)
                self.asset_bytes += len(data)
                if el.tag in ("texture", "hfield") and data.startswith(_PNG) and len(data) > 24:
                    w, h = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
                    if w * h > MAX_PIXELS:
                        raise self.bad(el, f"<{el.tag} {key}> {ref[:80]!r}: expected a PNG of "
                                           f"at most {MAX_PIXELS} pixels, got {w} x {h}")
                name = f"evomotion-asset-{len(self.asset_keys)}{PurePosixPath(ref).suffix}"
                self.asset_keys[real] = name
                self.assets[name] = data
            el.set(key, self.asset_keys[real])


_ASSETS: dict[str, dict[str, bytes]] = {}  # sha256 of a robot's MJCF text -> its assets
_MAX_REMEMBERED = 16


def remember_assets(xml: str, assets: dict[str, bytes]) -> None:
    """Keep the ``assets`` of the model text ``xml`` (a built robot's ``Robot.xml``), so that
    :func:`evomotion.sim.render.render_video` given only the text finds its meshes."""
    if assets:
        if len(_ASSETS) >= _MAX_REMEMBERED:
            _ASSETS.pop(next(iter(_ASSETS)))
        _ASSETS[hashlib.sha256(xml.encode()).hexdigest()] = assets


def assets_for(xml: str) -> dict[str, bytes]:
    """The assets remembered for the model text ``xml`` (``{}`` when none)."""
    return _ASSETS.get(hashlib.sha256(xml.encode()).hexdigest(), {})


def confined(ref: str, base: Path, root: Path) -> Path:
    """The real path of ``ref`` relative to the folder ``base``; ``ValueError`` (what was
    expected) unless it is a relative path without ``..`` whose real path (links followed)
    lies inside the real folder ``root``."""
    if not ref or "\0" in ref or "\\" in ref:
        raise ValueError("expected a relative path with '/' inside the robot's folder")
    rel = PurePosixPath(ref)
    if rel.is_absolute() or ref.startswith("~"):
        raise ValueError(f"expected a relative path inside {root}, got an absolute one")
    if ".." in rel.parts:
        raise ValueError(f"expected a path inside {root} ('..' leaves it)")
    real = Path(os.path.realpath(base / rel))
    if real != root and root not in real.parents:
        raise ValueError(f"a link leads outside {root} (to {real})")
    return real


def read_mjcf(path: Path, root: Path) -> MjcfBundle:
    """Read the MJCF at ``path`` (a real path inside the folder ``root``: :func:`confined`)
    and every file it names (see the module)."""
    root = Path(os.path.realpath(root))
    real = Path(os.path.realpath(path))
    reader = _Reader(real, root)
    reader.seen.add(real)
    tree = reader.load(real, real, None)
    reader.expand(tree, real.parent, (real,))
    reader.check(tree)
    sources: list[tuple[Path, int]] = []
    stack: list[tuple[ET.Element, bool]] = [(tree, False)]
    while stack:  # one line per start tag, one per closing tag of an element with children
        el, closing = stack.pop()
        sources.append(reader.where(el) if not closing else (real, 0))
        if closing or not len(el):
            el.tail = "\n"
            continue
        el.text, el.tail = "\n", "\n"
        stack.append((el, True))
        stack.extend((c, False) for c in reversed(el))
    tree.tail = None
    xml = ET.tostring(tree, encoding="unicode")
    return MjcfBundle(xml, reader.assets, real, hashlib.sha256(reader.main_bytes).hexdigest(),
                      tuple(reader.files), tuple(sources))
