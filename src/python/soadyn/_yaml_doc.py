"""Bounded reading of the YAML files a sweep names (soadyn.ensemble): a regular file's text, at
most MAX_FILE_BYTES; a scan of the parser's events that refuses a document nested deeper than
MAX_YAML_DEPTH, or of more than MAX_YAML_NODES nodes counting each alias as what it stands for,
before anything composes it; YAML 1.2's booleans and floats, as the scenario parser reads them; a
document's nodes with file:line:column messages; and text made printable for a terminal."""
from __future__ import annotations

import math
import os
import re
import stat
from typing import Any, Dict, List, Optional, Sequence, Tuple

import yaml

from ._soadyn import Error

MAX_FILE_BYTES = 16 << 20        # a sweep file, a base scenario
MAX_YAML_DEPTH = 64              # nested mappings and lists in a YAML document
MAX_YAML_NODES = 10_000_000      # a YAML document's nodes, each alias counted as what it stands for


# ---------------------------------------------------------------- text from files, text to a terminal

_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069\ud800-\udfff]")


def _escape(m) -> str:
    c = ord(m.group())
    if 0xdc80 <= c <= 0xdcff:  # a byte that was not UTF-8 (os.fsdecode's surrogateescape)
        return f"\\x{c - 0xdc00:02x}"
    return f"\\x{c:02x}" if c < 0x100 else f"\\u{c:04x}"


def printable(text: str) -> str:
    """text with every control character (C0, DEL, C1, bidirectional overrides) shown as \\xNN or
    \\uNNNN, as the C++ side's printable(): names and values read from files reach a terminal as
    text, never as escape sequences or line breaks."""
    return _CONTROL.sub(_escape, text)


def _clip(text: str, n: int = 60) -> str:
    """text for a one-line message: printable, and cut to n characters (saying how long it was)"""
    text = printable(text)
    return text if len(text) <= n else f"{text[:n]}… ({len(text)} characters)"


def _field(name: str) -> str:
    """a field's name for a one-line message: printable, its middle left out when long (a field
    2000 groups deep is vary[0].zip[0].zip[0]…zip[0].zip[0])"""
    name = printable(name)
    return name if len(name) <= 80 else f"{name[:45]}…{name[-30:]}"


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"))


def read_text(path: str, limit: int = MAX_FILE_BYTES) -> str:
    """A regular file's text (UTF-8, at most `limit` bytes); raises ValueError with the reason
    (the caller names the file and what it is for).  Opened without blocking, so a FIFO is refused,
    not waited on, and read to at most limit + 1 bytes, so /dev/zero or a growing file cannot
    fill the memory."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as e:
        raise ValueError(e.strerror) from None
    except ValueError:  # a NUL in the name
        raise ValueError("the name holds a NUL character") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            kind = next((k for test, k in _KINDS if test(st.st_mode)), "not a regular file")
            raise ValueError(f"{kind}, not a regular file")
        if st.st_size > limit:
            raise ValueError(f"{st.st_size} bytes, more than the {limit >> 20} MiB a file may have")
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(limit + 1)
    except OSError as e:
        raise ValueError(e.strerror) from None
    finally:
        os.close(fd)
    if len(data) > limit:
        raise ValueError(f"more than the {limit >> 20} MiB a file may have")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"not UTF-8 text (byte {e.start})") from None


# ---------------------------------------------------------------- reading the sweep file

def _yaml12(base):
    """A PyYAML loader whose booleans are YAML 1.2's (true, false) as in the scenario parser: a
    joint named y or n, or dynamics: on, stays a string; and 1e-2 is a number, as in YAML 1.2
    (PyYAML's YAML 1.1 floats need a dot)."""
    class Loader(base):
        pass
    Loader.yaml_implicit_resolvers = {k: [(tag, rx) for tag, rx in v if tag != "tag:yaml.org,2002:bool"]
                                      for k, v in base.yaml_implicit_resolvers.items()}
    Loader.add_implicit_resolver("tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
                                 list("tTfF"))
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", re.compile(r"^[-+]?[0-9]+[eE][-+]?[0-9]+$"),
                                 list("-+0123456789"))
    return Loader


_Loader = _yaml12(yaml.SafeLoader)
_FastLoader = _yaml12(getattr(yaml, "CSafeLoader", yaml.SafeLoader))


class _Open:
    """A mapping or list being scanned: its nodes so far, and where in it the scan is."""
    __slots__ = ("mapping", "size", "anchor", "items", "key", "at_key")

    def __init__(self, mapping: bool, anchor: Optional[str]):
        self.mapping, self.size, self.anchor, self.items, self.key, self.at_key = mapping, 1, anchor, 0, "", True

    def label(self, first: bool) -> str:
        if not self.mapping:
            return f"[{self.items}]"
        if self.at_key:
            return " (a key)"
        return self.key if first else "." + self.key


def check_yaml(text: str, path: str):
    """Refuse a YAML document nested more than MAX_YAML_DEPTH deep, or of more than MAX_YAML_NODES
    nodes counting each alias as the nodes it stands for, naming file:line:column and the field
    (vary[0].values[3]).  A scan of the parser's events (libyaml's where PyYAML has it), before
    any composing: PyYAML composes recursively (2000 nested lists end in RecursionError, libyaml's
    composer in a crash), and it shares an alias's node, but whatever walks the values afterwards
    (a JSON dump, a table) expands them: a billion laughs in 9 lines.  Each anchor's size is kept,
    so the scan is linear in the text however the aliases nest."""
    stack: List[_Open] = []
    anchors: Dict[str, int] = {}

    def refuse(event, message: str):
        m = event.start_mark
        field = _field("".join(e.label(k == 0) for k, e in enumerate(stack)))
        raise Error(f"{path}:{m.line + 1}:{m.column + 1}: " + (f"{field}: {message}" if field else message))

    def add(event, size: int, key: str = "?"):
        if not stack:
            return
        top = stack[-1]
        top.size += size
        if top.size > MAX_YAML_NODES:
            refuse(event, f"expands to more than {MAX_YAML_NODES} YAML nodes through aliases (the most a document "
                          "may hold: an alias bomb?)")
        if top.mapping and top.at_key:
            top.key, top.at_key = _clip(key, 40), False
        else:
            top.items += 1
            top.at_key = True

    try:
        for event in yaml.parse(text, Loader=_FastLoader):
            if isinstance(event, yaml.ScalarEvent):
                if event.anchor is not None:
                    anchors[event.anchor] = 1
                add(event, 1, event.value)
            elif isinstance(event, yaml.AliasEvent):
                size = anchors.get(event.anchor)
                if size is None:
                    held = any(e.anchor == event.anchor for e in stack)
                    refuse(event, f"the alias *{_clip(event.anchor, 40)} " + ("stands for a node that holds it (a "
                           "structure without end)" if held else "names no anchor before it"))
                add(event, size)
            elif isinstance(event, yaml.CollectionStartEvent):
                if len(stack) >= MAX_YAML_DEPTH:
                    refuse(event, f"nested more than {MAX_YAML_DEPTH} levels deep (the most a sweep file or "
                                  "scenario may nest)")
                stack.append(_Open(isinstance(event, yaml.MappingStartEvent), event.anchor))
            elif isinstance(event, yaml.CollectionEndEvent):
                done = stack.pop()
                if done.anchor is not None:
                    anchors[done.anchor] = done.size
                add(event, done.size)
            elif isinstance(event, yaml.DocumentEndEvent):
                anchors.clear()
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else path
        raise Error(f"{where}: not valid YAML: {printable(str(getattr(e, 'problem', e)))}") from None


class _Doc:
    """A YAML document's nodes, for values and file:line:column messages."""

    def __init__(self, text: str, path: str):
        self.path = path
        check_yaml(text, path)
        self.loader = _Loader(text)
        try:
            self.root = self.loader.get_single_node()
        except yaml.YAMLError as e:
            mark = getattr(e, "problem_mark", None)
            where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else path
            raise Error(f"{where}: not valid YAML: {printable(str(getattr(e, 'problem', e)))}") from None

    def where(self, node) -> str:
        m = node.start_mark
        return f"{self.path}:{m.line + 1}:{m.column + 1}"

    def fail(self, node, field: str, message: str):
        field = _field(field)
        raise Error(f"{self.where(node)}: {field}: {message}" if field else f"{self.where(node)}: {message}")

    def value(self, node, field: str = ""):
        """the node as Python data (tags PyYAML's safe loader does not know, or an integer of more
        digits than Python converts, are refused at the node)"""
        try:
            return self.loader.construct_object(node, deep=True)
        except yaml.YAMLError as e:
            self.fail(node, field, f"cannot read this value: {printable(str(getattr(e, 'problem', e)))}")
        except (ValueError, TypeError, OverflowError) as e:
            self.fail(node, field, f"cannot read this value: {printable(str(e))}")

    def mapping(self, node, field: str, allowed: Sequence[str]) -> Dict[str, Any]:
        if not isinstance(node, yaml.MappingNode):
            # the whole file not a mapping (another kind of file, named by mistake): not quoted back
            got = "plain text: is this the right file?" if node is self.root and isinstance(node, yaml.ScalarNode) and node.value else _show(node)
            self.fail(node, field, f"expected a mapping, got {got}")
        out = {}
        for k, v in node.value:
            key = self.value(k, field)
            name = f"{field}.{key}" if field else str(key)
            if not isinstance(key, str) or key not in allowed:
                self.fail(k, name, f"unknown field (expected one of {', '.join(allowed)})")
            if key in out:
                self.fail(k, name, "given twice")
            out[key] = v
        return out

    def number(self, node, field: str, positive=False) -> float:
        """a finite number (an int or a float, not a boolean), as written"""
        v = self.value(node, field)
        ok = isinstance(v, (int, float)) and not isinstance(v, bool)
        if ok:
            try:
                x = float(v)
            except OverflowError:
                self.fail(node, field, f"expected a finite number, got {_show(node)} (too large)")
            ok = math.isfinite(x) and (x > 0 or not positive)
        if not ok:
            self.fail(node, field, f"expected {'a positive' if positive else 'a finite'} number, got {_show(node)}")
        return v

    def integer(self, node, field: str, low: int, high: Optional[int], what: str) -> int:
        """an integer in [low, high] (high None: no bound; not a float, not a boolean)"""
        v = self.value(node, field)
        if not isinstance(v, int) or isinstance(v, bool) or v < low or (high is not None and v > high):
            self.fail(node, field, f"expected {what}, got {_show(node)}")
        return v

    def pair(self, node, field: str) -> Tuple[float, float]:
        if not isinstance(node, yaml.SequenceNode) or len(node.value) != 2:
            self.fail(node, field, f"expected [a, b], got {_show(node)}")
        return self.number(node.value[0], field + "[0]"), self.number(node.value[1], field + "[1]")


def _show(node) -> str:
    if isinstance(node, yaml.ScalarNode):
        return f"'{_clip(node.value)}'"
    return {yaml.MappingNode: "a mapping", yaml.SequenceNode: "a list"}.get(type(node), "nothing")


def _plain(value, seen=None) -> Optional[str]:
    """None if value is what JSON carries to the scenario parser (a string, a finite number, a
    boolean, null, or lists and string-keyed mappings of them), else what is wrong with it"""
    if isinstance(value, (str, bool, int)) or value is None:
        return None
    if isinstance(value, float):
        return None if math.isfinite(value) else f"expected a finite number, got {value}"
    seen = set() if seen is None else seen
    if id(value) in seen:  # an alias: checked where it was first met
        return None
    seen.add(id(value))
    if isinstance(value, list):
        return next((e for e in (_plain(v, seen) for v in value) if e), None)
    if isinstance(value, dict):
        if not all(isinstance(k, str) for k in value):
            return "expected a mapping with names as keys"
        return next((e for e in (_plain(v, seen) for v in value.values()) if e), None)
    return f"expected a number, a string, or a list or mapping of them, got a {type(value).__name__}"
