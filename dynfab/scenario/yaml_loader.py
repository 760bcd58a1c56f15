"""Reading a scenario file that nobody checked: the YAML text is refused, with a one-line
:class:`ScenarioError`, before anything is built from it when

- the file is larger than :data:`MAX_FILE_BYTES` (1 MB);
- it is not UTF-8 text (a UTF-16 or UTF-32 byte order mark, an invalid byte such as a
  Latin-1 ``é``, NUL bytes of a binary file); a UTF-8 byte order mark is allowed;
- it is not valid YAML (line and column given);
- collections nest deeper than :data:`MAX_DEPTH` levels;
- aliases (``*name``) would expand the document to more than :data:`MAX_NODES` values
  (an "alias bomb"); aliases within the budget are allowed;
- a mapping repeats a key (YAML requires unique keys).

The checks run on the parser's event stream (no recursion, no expansion); only a
document that passes is constructed, with ``safe_load`` semantics (no code, no objects).
"""

from __future__ import annotations

import codecs
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from dynfab.scenario.fields import ScenarioError, join, yaml_problem

__all__ = ["MAX_DEPTH", "MAX_FILE_BYTES", "MAX_NODES", "load_yaml_file", "parse_yaml"]

#: Largest scenario file [bytes].
MAX_FILE_BYTES = 1_000_000
#: Deepest nesting of lists and mappings.
MAX_DEPTH = 32
#: Most values (scalars, lists, mappings) of the document with every alias expanded.
MAX_NODES = 50_000

_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_BOMS = ((codecs.BOM_UTF32_LE, "UTF-32"), (codecs.BOM_UTF32_BE, "UTF-32"),
         (codecs.BOM_UTF16_LE, "UTF-16"), (codecs.BOM_UTF16_BE, "UTF-16"))
_MERGE_TAG = "tag:yaml.org,2002:merge"
#: Components of a field path shown in a message about nesting or aliases.
_SHOWN_COMPONENTS = 6


def load_yaml_file(path: Path) -> object:
    """The YAML document of ``path``, read under the limits above.

    Raises:
        ScenarioError: On ``path`` (or the field where the problem is): unreadable, too
            large, not UTF-8, invalid YAML, too deep, too many values, a duplicate key.
    """
    try:
        with path.open("rb") as file:
            data = file.read(MAX_FILE_BYTES + 1)
    except OSError as error:
        raise ScenarioError(str(path), f"cannot read file ({error.strerror})") from None
    if len(data) > MAX_FILE_BYTES:
        raise ScenarioError(str(path), f"file larger than {MAX_FILE_BYTES} bytes, the limit of a scenario file")
    return parse_yaml(_utf8_text(data, str(path)), str(path))


def parse_yaml(text: str, source: str) -> object:
    """The YAML document of ``text`` (from ``source``, named in YAML syntax errors)."""
    try:
        _check_events(text)
        return yaml.load(text, Loader=_LOADER)  # noqa: S506 - a safe loader
    except yaml.YAMLError as error:
        raise ScenarioError(source, yaml_problem(error)) from None


def _utf8_text(data: bytes, source: str) -> str:
    """``data`` decoded as UTF-8 (a leading byte order mark dropped)."""
    for bom, encoding in _BOMS:
        if data.startswith(bom):
            raise ScenarioError(source, f"not UTF-8 text: the file starts with a {encoding} byte order mark; "
                                "save it as UTF-8")
    if b"\0" in data:
        line = data[:data.index(b"\0")].count(b"\n") + 1
        raise ScenarioError(source, f"not UTF-8 text: NUL byte at line {line} (a binary file?)")
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise ScenarioError(source, f"not UTF-8 text: byte 0x{data[error.start]:02x} at line {line} is not "
                            "valid UTF-8 (a Latin-1 or Windows character?); save the file as UTF-8") from None


@dataclass
class _Frame:
    """An open list or mapping of the event stream."""

    name: str
    start: int
    is_mapping: bool
    anchor: str | None
    index: int = 0
    key: str | None = None
    keys: set[tuple[str, str]] = field(default_factory=set)
    height: int = 0


class _Budget:
    """Depth, expanded size and unique keys of the document, event by event."""

    def __init__(self) -> None:
        self.frames: list[_Frame] = []
        self.nodes = 0
        self.anchors: dict[str, tuple[int, int]] = {}
        self.resolver = yaml.resolver.Resolver()

    def field(self, key: str | None = None) -> str:
        """Path of the current position (its first components only), or of ``key`` here."""
        path = ""
        for frame in self.frames[1:_SHOWN_COMPONENTS + 1]:
            path = path + frame.name if frame.name.startswith("[") else join(path, frame.name)
        if key is not None:
            return join(path, key)
        path = "scenario" + path if not path or path.startswith("[") else path
        return path + ("..." if len(self.frames) > _SHOWN_COMPONENTS + 1 else "")

    def child_name(self, event: yaml.NodeEvent) -> str | None:
        """The name of the node that starts with ``event`` in the open frame; None for a key."""
        if not self.frames:
            return ""
        frame = self.frames[-1]
        if not frame.is_mapping:
            frame.index += 1
            return f"[{frame.index - 1}]"
        if frame.key is None:
            return None
        name, frame.key = frame.key, None
        return name

    def add(self, size: int, height: int, mark: yaml.Mark) -> None:
        """Count a node of ``size`` expanded values with ``height`` levels of collections."""
        self.nodes += size
        if self.nodes > MAX_NODES:
            raise ScenarioError(self.field(), f"the document expands to more than {MAX_NODES} "
                                f"values (YAML aliases?) at line {mark.line + 1}")
        if len(self.frames) + height > MAX_DEPTH:
            raise ScenarioError(self.field(), f"lists and mappings nest deeper than {MAX_DEPTH} "
                                f"levels at line {mark.line + 1}")
        if self.frames:
            self.frames[-1].height = max(self.frames[-1].height, height)

    def key(self, event: yaml.NodeEvent) -> None:
        """Record a mapping key; refuse a repeated one."""
        frame = self.frames[-1]
        if isinstance(event, yaml.ScalarEvent):
            tag = event.tag or self.resolver.resolve(yaml.ScalarNode, event.value, event.implicit)
            if tag != _MERGE_TAG and (tag, event.value) in frame.keys:
                raise ScenarioError(self.field(event.value), f"duplicate key (line {event.start_mark.line + 1}; "
                                    "YAML requires unique keys)")
            frame.keys.add((tag, event.value))
            frame.key = event.value
        else:
            frame.key = "?"


def _check_events(text: str) -> None:
    """Walk the parser's events and refuse what the module docstring lists."""
    budget = _Budget()
    for event in yaml.parse(text, Loader=yaml.SafeLoader):  # lazy: libyaml's parser reads ahead and stops
        # at its own nesting limit (1000 levels, PyYAML >= 6.0.3) before this check can name the field
        if isinstance(event, yaml.CollectionEndEvent):
            frame = budget.frames.pop()
            if frame.anchor:
                budget.anchors[frame.anchor] = (budget.nodes - frame.start + 1, frame.height + 1)
            if budget.frames:
                budget.frames[-1].height = max(budget.frames[-1].height, frame.height + 1)
            continue
        if not isinstance(event, yaml.NodeEvent):
            continue
        name = budget.child_name(event)
        if name is None:
            budget.key(event)
        if isinstance(event, yaml.AliasEvent):
            budget.add(*budget.anchors.get(event.anchor, (1, 0)), event.start_mark)
        elif isinstance(event, yaml.ScalarEvent):
            budget.add(1, 0, event.start_mark)
            if event.anchor:
                budget.anchors[event.anchor] = (1, 0)
        else:
            budget.add(1, 1, event.start_mark)
            budget.frames.append(_Frame("?" if name is None else name, budget.nodes,
                                        isinstance(event, yaml.MappingStartEvent), event.anchor))
