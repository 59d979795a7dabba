"""Scenario files: the YAML schema, a loader with line-accurate E-SCENARIO diagnostics, and name binding."""

from __future__ import annotations

import dataclasses
import difflib
import fnmatch
import functools
import re
from decimal import Decimal, InvalidOperation
from pathlib import Path
from types import MappingProxyType
from typing import Annotated, Any, Callable, Iterator, Literal, Mapping, NamedTuple, Union, get_args

import yaml
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, \
    model_validator

from transpiler.diagnostics import CompileFailed, Diagnostic, Diagnostics, Span
from transpiler.ir import VALUE_RANGES, sext
from transpiler.language.semantics import PROFILES

# ---------------------------------------------------------------------------------------------
# Operands and names


class OperandRef(NamedTuple):
    """An absolute operand: kind letter (M I O T C B W D S) and address (byte address for B/W/D)."""

    kind: str
    addr: int

    def __str__(self) -> str:
        return f"{self.kind}{self.addr}"


BIT_KINDS = frozenset("MIOTC")
WIDTHS: Mapping[str, int] = {"B": 8, "W": 16, "D": 32}
# Column order of default traces: inputs first, then outputs, markers, timers, counters, memory.
KIND_ORDER = "IOMTCBWDS"

_RAW_OPERAND = re.compile(r"\s*([MIOTCBWDS])\s*(\d+)\s*", re.IGNORECASE)
_GLOB_CHARS = frozenset("*?[")


def parse_operand(text: str) -> OperandRef | None:
    """Raw operand syntax (`I5`, `m 1000`, `W262`): the operand, or None when `text` is not one."""
    match = _RAW_OPERAND.fullmatch(text)
    if match is None:
        return None
    return OperandRef(match.group(1).upper(), int(match.group(2)))


def is_glob(pattern: str) -> bool:
    return any(c in _GLOB_CHARS for c in pattern)


def normalize_value(kind: str, value: Any) -> int | str:
    """Canonical form of an operand value: 0/1 for bits, signed two's complement for B/W/D, str for S."""
    if kind == "S":
        return str(value)
    if kind in WIDTHS:
        return sext(int(value), WIDTHS[kind])
    return 1 if value else 0


def values_equal(kind: str, expected: Any, actual: Any) -> bool:
    """The test-vector rule: B/W/D compare modulo 2^width (0xFC == -4 for a byte), bits as 0/1, S as text."""
    if kind == "S":
        return str(expected) == str(actual)
    try:
        return normalize_value(kind, expected) == normalize_value(kind, actual)
    except (TypeError, ValueError):
        return False


def _aligned(ref: OperandRef) -> bool:
    return ref.kind not in ("W", "D") or ref.addr % (2 if ref.kind == "W" else 4) == 0


@dataclasses.dataclass(frozen=True)
class NameTable:
    """What the project knows about names, supplied by the caller.

    symbols: every symbol of the .def files (aliases included) plus every raw operand name the
        program uses (`"I5"`), mapped to its operand; matched case-sensitively.
    writable_inputs: further operand names (e.g. `"I18"`) that globs in `random.inputs` and
        `observe` may match although the program does not use them.
    ranges_ok: whether an operand address exists on the profile (for B/W/D: the byte address).
    non_toggle: names of aliases (&) and constants; random stimulus never toggles them.
    constants: names of constant symbols (K); they cannot be set, expected or observed.
    table_rows: the symbols the project's PLC data tables set (MP_Data.tab, MP_Config.tab), which a scenario's
        `mp_data` may give other values.
    """

    symbols: Mapping[str, OperandRef]
    writable_inputs: frozenset[str]
    ranges_ok: Callable[[str, int], bool]
    non_toggle: frozenset[str] = frozenset()
    constants: frozenset[str] = frozenset()
    table_rows: Mapping[str, OperandRef] = dataclasses.field(default_factory=dict)   # data-table row symbols

    @classmethod
    def for_profile(cls, symbols: Mapping[str, OperandRef], profile: str = "itnc530", *,
                    writable_inputs: frozenset[str] = frozenset(), non_toggle: frozenset[str] = frozenset(),
                    constants: frozenset[str] = frozenset(),
                    table_rows: Mapping[str, OperandRef] | None = None) -> NameTable:
        """A table whose range check is the address ranges of a profile of the language spec."""
        ranges = PROFILES[profile].ranges

        def ranges_ok(kind: str, addr: int) -> bool:
            if kind in WIDTHS:
                return all(ranges.contains("B", a) for a in range(addr, addr + WIDTHS[kind] // 8))
            return ranges.contains(kind, addr)

        return cls(symbols, writable_inputs, ranges_ok, non_toggle, constants, MappingProxyType(dict(table_rows or {})))

    def resolve(self, name: str) -> OperandRef:
        """The operand a scenario name denotes; raises NameProblem with a user-facing message."""
        if name in self.constants:
            raise NameProblem(f"'{name}' is a constant; only operands can be set, expected or observed")
        ref = self.symbols.get(name)
        if ref is None:
            ref = parse_operand(name)
        if ref is None:
            hint = difflib.get_close_matches(name, list(self.symbols), n=1)
            suffix = f" (did you mean '{hint[0]}'?)" if hint else ""
            raise NameProblem(f"unknown name '{name}': neither a symbol of the project nor an operand{suffix}")
        if not _aligned(ref):
            raise NameProblem(f"{label(name, ref)} is misaligned: W addresses are even, D addresses multiples of 4")
        if not self.ranges_ok(ref.kind, ref.addr):
            raise NameProblem(f"{label(name, ref)} is outside the operand range of the profile")
        return ref

    @functools.cached_property
    def universe(self) -> tuple[str, ...]:
        """Every name a glob may match, sorted."""
        return tuple(sorted(set(self.symbols) | set(self.writable_inputs)))

    def match(self, pattern: str) -> list[str]:
        """Names matching a glob (fnmatch, case-sensitive), sorted."""
        return [n for n in self.universe if fnmatch.fnmatchcase(n, pattern)]

    @functools.cached_property
    def _display(self) -> dict[OperandRef, str]:
        names: dict[OperandRef, str] = {}
        for name in sorted(self.symbols):
            if parse_operand(name) is None and name not in self.constants:
                names.setdefault(self.symbols[name], name)
        return names

    def display_name(self, ref: OperandRef) -> str:
        """The first symbol (sorted) naming the operand, else the raw operand."""
        return self._display.get(ref, str(ref))


class NameProblem(ValueError):
    """A scenario name that does not denote a usable operand."""


def label(name: str, ref: OperandRef) -> str:
    """How messages name an operand: 'O_lamp (O5)', or just 'O5' for a raw operand."""
    return name if parse_operand(name) == ref else f"{name} ({ref})"


def check_value(ref: OperandRef, value: Any) -> str | None:
    """Why `value` cannot be written to or expected of `ref`, or None when it can."""
    if ref.kind == "S":
        return None if isinstance(value, str) else f"a string operand expects text, not {value!r}"
    if isinstance(value, bool) or not isinstance(value, int):
        wanted = "0 or 1" if ref.kind in BIT_KINDS else "an integer"
        return f"expects {wanted}, not {value!r}"
    if ref.kind in BIT_KINDS:
        return None if value in (0, 1) else f"a bit operand expects 0 or 1, not {value}"
    lo, hi = VALUE_RANGES[ref.kind]
    if lo <= value <= hi:
        return None
    return f"value {value} does not fit in {WIDTHS[ref.kind]} bits ({lo}..{hi})"


# ---------------------------------------------------------------------------------------------
# Schema


class _Model(BaseModel):
    # strict: YAML already gives typed scalars, so "300" for an integer is a mistake worth reporting
    model_config = ConfigDict(extra="forbid", strict=True)


# The values an NC action may carry: what the control sends (numbers, a pocket -1 for "none"), positive in the
# signed range of the interface word, so that the program reads them as given. The NC model writes them to its
# interface words unchanged, so these bounds are also the values those words can hold (nc_facts.py claims no other
# value there, and a TOOL CALL's pocket >= 1 is one the program reads as >= 1).
_SIGNED_MAX = {"W": (1 << 15) - 1, "D": (1 << 31) - 1}
NC_VALUE_RANGES: Mapping[str, tuple[int, int]] = MappingProxyType({
    "m_function": (0, _SIGNED_MAX["W"]), "gear": (0, _SIGNED_MAX["W"]), "mode": (0, _SIGNED_MAX["W"]),
    "tool": (0, _SIGNED_MAX["W"]), "pocket": (-1, _SIGNED_MAX["W"]),
    "spindle_speed": (0, _SIGNED_MAX["D"]), "fn19": VALUE_RANGES["D"]})


def _nc_value(field: str):
    low, high = NC_VALUE_RANGES[field]
    return Annotated[int, Field(ge=low, le=high)]


_DWord = Annotated[int, Field(ge=VALUE_RANGES["D"][0], le=VALUE_RANGES["D"][1])]


class ToolCall(_Model):
    tool: _nc_value("tool")
    pocket: _nc_value("pocket")
    second_strobe: bool = False


class ToolDef(_Model):
    tool: _nc_value("tool")
    pocket: _nc_value("pocket")


class Fn19(_Model):
    value1: _nc_value("fn19")
    value2: _nc_value("fn19")


NC_KINDS = ("m_function", "spindle_speed", "gear", "tool_call", "tool_def", "fn19", "mode", "restart")


class NcAction(_Model):
    """One NC-model action (scenario format); exactly one field is set."""

    m_function: _nc_value("m_function") | None = None
    spindle_speed: _nc_value("spindle_speed") | None = None
    gear: _nc_value("gear") | None = None
    tool_call: ToolCall | None = None
    tool_def: ToolDef | None = None
    fn19: Fn19 | None = None
    mode: _nc_value("mode") | None = None
    restart: Literal["program", "machine_parameters"] | None = None

    @model_validator(mode="after")
    def _exactly_one(self) -> NcAction:
        given = [k for k in NC_KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            found = ", ".join(given) if given else "none"
            raise ValueError(f"an nc action has exactly one of {', '.join(NC_KINDS)} (found: {found})")
        return self

    @property
    def kind(self) -> str:
        return next(k for k in NC_KINDS if getattr(self, k) is not None)

    def as_dict(self) -> dict[str, Any]:
        """The plain form for the NC model, e.g. {'tool_call': {'tool': 5, 'pocket': 2, 'second_strobe': False}}."""
        return self.model_dump(exclude_none=True)


# The tables selected for program run that PLC modules 9092-9094 read and write, by the file type they use.
TABLE_FILES: Mapping[str, int] = MappingProxyType({"T": 0, "D": 1, "TCH": 2})
AXES = 16
TABLE_ELEMENTS = 63
STATUS_ENTRIES = 256        # entries of the NC status table modules 9035/9036 read and write (the C model's size)


class Axis(_Model):
    """One NC axis as the PLC modules see it: whether it exists and is active, and its actual position."""

    active: bool = True
    position: _DWord = 0            # actual position in the reference system, 0.0001 mm (module 9049)


class Drives(_Model):
    """Power stages: bit n = drive of axis n+1 (bit 15 the spindle)."""

    available: _DWord               # ready to be switched on (module 9162 gives available AND enabled)
    switching_off: _DWord = 0       # early warning that a drive is about to be switched off (module 9159)


class TableEntry(_Model):
    """One element of a tool (T), datum (D) or pocket (TCH) table selected for program run."""

    table: Literal["T", "D", "TCH"]
    line: Annotated[int, Field(ge=0, le=VALUE_RANGES["D"][1])]
    element: Annotated[int, Field(ge=0, le=TABLE_ELEMENTS)]
    value: _DWord


class MachineData(_Model):
    """What the control's PLC modules read about the machine: axes, drives, table contents, NC status values."""

    axes: dict[Annotated[int, Field(ge=0, lt=AXES)], Axis] = {}
    drives: Drives | None = None
    tables: list[TableEntry] = []
    status: dict[Annotated[int, Field(ge=0, lt=STATUS_ENTRIES)], _DWord] = {}   # NC status information (9035)

    @model_validator(mode="after")
    def _not_empty(self) -> MachineData:
        if not self.axes and self.drives is None and not self.tables and not self.status:
            raise ValueError("`machine` needs `axes`, `drives`, `tables` or `status`")
        return self

    def as_dict(self) -> dict[str, Any]:
        return self.model_dump(exclude_none=True, exclude_defaults=False)


class Event(_Model):
    cycle: Annotated[int, Field(ge=0)]
    set: dict[str, Any] = {}
    nc: NcAction | None = None
    machine: MachineData | None = None

    @model_validator(mode="after")
    def _not_empty(self) -> Event:
        if not self.set and self.nc is None and self.machine is None:
            raise ValueError("an event needs `set`, `nc` or `machine`")
        return self


class RandomStimulus(_Model):
    seed: int
    inputs: Annotated[list[str], Field(min_length=1)]
    toggle_probability: Annotated[float, Field(ge=0.0, le=1.0)] = 0.05


class Expectation(_Model):
    cycle: Annotated[int, Field(ge=0)]
    values: Annotated[dict[str, Any], Field(min_length=1)]


def _scalar(value: Any) -> Any:
    if isinstance(value, (bool, int, float, str)):
        return value
    raise ValueError(f"expected a scalar (number, true/false or text), not {value!r}")


MpKey = tuple[int, Union[int, None]]


class Scenario(_Model):
    """A validated scenario. `mp` keys are (parameter number, index or None)."""

    name: str = "scenario"
    cycles: Annotated[int, Field(gt=0)]
    cycle_time_ms: Annotated[int, Field(gt=0)] = 20
    profile: str = "itnc530"
    machine_parameters: Annotated[Path | None, Field(strict=False)] = None
    mp: dict[MpKey, Decimal] = {}
    mp_data: dict[str, Annotated[Any, AfterValidator(_scalar)]] = {}    # data-table rows: symbol -> value
    initial: dict[str, Any] = {}
    events: list[Event] = []
    random: RandomStimulus | None = None
    observe: list[str] | None = None
    expect: list[Expectation] = []
    semantics: dict[str, Annotated[Any, AfterValidator(_scalar)]] = {}
    module_results: dict[int, list[int]] = {}
    machine: MachineData | None = None

    _source: Path | None = PrivateAttr(default=None)
    _spans: dict[tuple, Span] = PrivateAttr(default_factory=dict)
    _key_spans: dict[tuple, Span] = PrivateAttr(default_factory=dict)
    _refs: dict[str, OperandRef] = PrivateAttr(default_factory=dict)
    _warnings: tuple[Diagnostic, ...] = PrivateAttr(default=())

    @field_validator("profile")
    @classmethod
    def _known_profile(cls, value: str) -> str:
        if value not in PROFILES:
            raise ValueError(f"unknown profile {value!r} (known: {', '.join(PROFILES)})")
        return value

    def __eq__(self, other: object) -> bool:
        # equal content is an equal scenario, wherever it was loaded from
        if not isinstance(other, Scenario):
            return NotImplemented
        return self.__dict__ == other.__dict__

    @property
    def source(self) -> Path | None:
        """The file the scenario was loaded from (None when built in code)."""
        return self._source

    @property
    def warnings(self) -> tuple[Diagnostic, ...]:
        return self._warnings

    def span_of(self, *path: Any) -> Span:
        """Span of the YAML value at `path` (e.g. 'events', 3, 'cycle'), or of its nearest enclosing node."""
        return _nearest(self._spans, path, self._file_span())

    def key_span_of(self, *path: Any) -> Span:
        """Span of the YAML key at `path`, falling back to the value's span."""
        return self._key_spans.get(tuple(path)) or self.span_of(*path)

    def ref(self, name: str) -> OperandRef | None:
        """The operand a name of this scenario was bound to (after load_scenario or bind)."""
        return self._refs.get(name)

    def _file_span(self) -> Span:
        return Span(str(self._source) if self._source else "<scenario>", 1, 1)


def _nearest(spans: Mapping[tuple, Span], path: tuple, default: Span) -> Span:
    path = tuple(path)
    while path:
        if path in spans:
            return spans[path]
        path = path[:-1]
    return spans.get((), default)


class ScenarioError(CompileFailed):
    """A scenario that cannot be used; carries every E-SCENARIO diagnostic found."""


# ---------------------------------------------------------------------------------------------
# YAML with positions


@dataclasses.dataclass
class _Tree:
    """Plain Python data built from YAML nodes, with the span of every value, key and key text."""

    file: str
    diags: Diagnostics
    spans: dict[tuple, Span] = dataclasses.field(default_factory=dict)
    key_spans: dict[tuple, Span] = dataclasses.field(default_factory=dict)
    key_text: dict[tuple, str] = dataclasses.field(default_factory=dict)
    scalar_text: dict[tuple, str] = dataclasses.field(default_factory=dict)
    broken: set[tuple] = dataclasses.field(default_factory=set)   # values already reported as unreadable

    def span(self, mark: yaml.Mark) -> Span:
        return Span(self.file, mark.line + 1, mark.column + 1)

    def build(self, node: yaml.Node, path: tuple = ()) -> Any:
        self.spans[path] = self.span(node.start_mark)
        if isinstance(node, yaml.MappingNode):
            return self._mapping(node, path)
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, path + (i,)) for i, item in enumerate(node.value)]
        self.scalar_text[path] = node.value
        return self._scalar(node, path)

    def _mapping(self, node: yaml.MappingNode, path: tuple) -> dict:
        result: dict = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                self.diags.report("E-SCENARIO", self.span(key_node.start_mark), "a key must be a plain name or number")
                continue
            # an unreadable key (e.g. the merge key '<<') is kept as text: the schema reports it as unknown
            key = self._scalar(key_node, None)
            try:
                hash(key)
            except TypeError:
                key = key_node.value
            if key in result:
                self.diags.report("E-SCENARIO", self.span(key_node.start_mark), f"duplicate key '{key_node.value}'")
                continue
            sub = path + (key,)
            self.key_spans[sub] = self.span(key_node.start_mark)
            self.key_text[sub] = key_node.value
            result[key] = self.build(value_node, sub)
        return result

    def _scalar(self, node: yaml.ScalarNode, path: tuple | None) -> Any:
        try:
            return yaml.constructor.SafeConstructor().construct_object(node)
        except (yaml.YAMLError, ValueError) as exc:
            if path is not None:
                problem = getattr(exc, "problem", None) or str(exc)
                self.diags.report("E-SCENARIO", self.span(node.start_mark), f"bad value {node.value!r}: {problem}")
                self.broken.add(path)
            return node.value


def _number_text(number: int) -> str:
    """A number for a message: written out unless it is absurdly long."""
    text = str(number)
    return text if len(text) <= 24 else f"{text[:8]}... ({len(text)} digits)"


def _codepoint(character: int | str) -> str:
    return f"U+{character if isinstance(character, int) else ord(character):04X}"


# Bounds of what a scenario file may be, so that no file makes the loader recurse without end or expand aliases
# without end (a "billion laughs" file is a few lines long). The scenario format itself nests 6 levels deep.
MAX_NESTING = 32                 # levels of mappings and lists, aliases expanded
MAX_ALIAS_VALUES = 100_000       # values of a file whose aliases make it larger than it is written
MAX_CYCLES = 1_000_000           # cycles of one scenario file: about 5.5 hours of machine time at 20 ms


class _Refused(yaml.MarkedYAMLError):
    """Well-formed YAML the scenario loader does not compose (too deep, an alias inside itself, an alias bomb)."""

    def __init__(self, mark: yaml.Mark, problem: str):
        super().__init__(problem=problem, problem_mark=mark)


class _BoundedLoader(yaml.SafeLoader):
    """The safe YAML loader with bounded nesting and without values that contain themselves. (PyYAML composes
    recursively: a file nested thousands of levels deep would otherwise exhaust Python's stack.)"""

    def __init__(self, stream: str):
        super().__init__(stream)
        self.depth = 0
        self.open_anchors: set[str] = set()      # anchors whose value is being composed

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            if event.anchor in self.open_anchors:
                raise _Refused(event.start_mark, f"alias *{event.anchor} is inside the value of its own anchor "
                                                 f"&{event.anchor}: a value cannot contain itself")
            return super().compose_node(parent, index)
        if self.depth >= MAX_NESTING:
            raise _Refused(event.start_mark, f"nested deeper than {MAX_NESTING} levels")
        anchor = getattr(event, "anchor", None)
        self.depth += 1
        if anchor is not None:
            self.open_anchors.add(anchor)
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1
            self.open_anchors.discard(anchor)


def _expansion(root: yaml.Node) -> tuple[int, int, int]:
    """(values, nesting levels) of the document with every alias expanded, and its distinct nodes. Each node is
    visited once (aliases make a DAG of the nodes, never a cycle: _BoundedLoader refuses those)."""
    size: dict[int, int] = {}
    height: dict[int, int] = {}
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if id(node) in size:
            continue
        if isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        elif isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        else:
            children = []
        if not children_done:
            stack.append((node, True))
            stack.extend((child, False) for child in children if id(child) not in size)
            continue
        size[id(node)] = 1 + sum(size[id(child)] for child in children)
        height[id(node)] = 1 + max((height[id(child)] for child in children), default=0)
    return size[id(root)], height[id(root)], len(size)


def compose_yaml(text: str) -> yaml.Node | None:
    """The YAML node tree of a scenario text within the bounds above; raises yaml.YAMLError (a MarkedYAMLError
    with a position for a refused file)."""
    loader = _BoundedLoader(text)
    try:
        root = loader.get_single_node()
    finally:
        loader.dispose()
    if root is None:
        return None
    values, levels, distinct = _expansion(root)
    if levels > MAX_NESTING:
        raise _Refused(root.start_mark, f"with its aliases expanded, the scenario is nested deeper than {MAX_NESTING} "
                                        "levels")
    if values > max(MAX_ALIAS_VALUES, distinct):
        raise _Refused(root.start_mark, f"its aliases expand the scenario to {values} values, more than the "
                                        f"{MAX_ALIAS_VALUES} a scenario may have (an alias bomb?)")
    return root


def _compose(text: str, file: str, diags: Diagnostics) -> yaml.Node | None:
    try:
        return compose_yaml(text)
    except _Refused as exc:
        mark = exc.problem_mark
        diags.report("E-SCENARIO", Span(file, mark.line + 1, mark.column + 1), f"scenario refused: {exc.problem}")
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        span = Span(file, mark.line + 1, mark.column + 1) if mark else Span(file, 1, 1)
        problem = exc.problem or exc.context or "malformed YAML"
        diags.report("E-SCENARIO", span, f"YAML syntax error: {problem}")
    except yaml.reader.ReaderError as exc:
        line = text[:exc.position].count("\n") + 1
        col = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        diags.report("E-SCENARIO", Span(file, line, col), f"YAML syntax error: {exc.reason} ({_codepoint(exc.character)})")
    except yaml.YAMLError as exc:
        diags.report("E-SCENARIO", Span(file, 1, 1), f"YAML syntax error: {exc}")
    return None


# ---------------------------------------------------------------------------------------------
# Pre-validation conversions (machine parameters)

_MP_KEY = re.compile(r"\s*(?:MP\s*)?(\d+)(?:\.(\d+))?\s*", re.IGNORECASE)


def parse_mp_key(text: str) -> MpKey | None:
    """'4110.3' -> (4110, 3); '7210' -> (7210, None); an optional 'MP' prefix is accepted."""
    match = _MP_KEY.fullmatch(text)
    if match is None:
        return None
    return int(match.group(1)), int(match.group(2)) if match.group(2) is not None else None


def mp_key_text(key: MpKey) -> str:
    return f"{key[0]}" if key[1] is None else f"{key[0]}.{key[1]}"


def _mp_value(value: Any, text: str | None) -> Decimal | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return Decimal(value)
    raw = text if isinstance(value, float) and text is not None else value
    if not isinstance(raw, (str, float)):
        return None
    raw = str(raw).strip().replace("_", "")
    try:
        if raw.startswith("$"):
            return Decimal(int(raw[1:], 16))
        if raw.startswith("%"):
            return Decimal(int(raw[1:], 2))
        number = Decimal(raw)
    except (InvalidOperation, ValueError):
        return None
    return number if number.is_finite() else None


def _convert_mp(data: dict, tree: _Tree) -> None:
    raw = data.get("mp")
    if not isinstance(raw, dict):
        return
    converted: dict[MpKey, Decimal] = {}
    for key, value in raw.items():
        path = ("mp", key)
        text = tree.key_text.get(path, str(key))
        mp_key = parse_mp_key(text)
        if mp_key is None:
            tree.diags.report("E-SCENARIO", tree.key_spans.get(path, tree.spans[("mp",)]),
                             f"machine parameter '{text}' is not of the form \"4110.3\"")
            continue
        number = _mp_value(value, tree.scalar_text.get(path))
        if number is None:
            tree.diags.report("E-SCENARIO", tree.spans.get(path, tree.spans[("mp",)]),
                             f"machine parameter {text}: {value!r} is not a number")
            continue
        if mp_key in converted:
            tree.diags.report("E-SCENARIO", tree.key_spans[path], f"machine parameter {text} is given twice")
            continue
        converted[mp_key] = number
        tree.spans[("mp", mp_key)] = tree.spans[path]
        tree.key_spans[("mp", mp_key)] = tree.key_spans[path]
    data["mp"] = converted


def _resolve_mp_file(data: dict, folder: Path, tree: _Tree) -> None:
    value = data.get("machine_parameters")
    if not isinstance(value, str):
        return  # a wrong type is reported by the schema
    resolved = (folder / value).resolve()
    if not resolved.is_file():
        tree.diags.report("E-SCENARIO", tree.spans[("machine_parameters",)],
                         f"machine-parameter file not found: {resolved}")
    data["machine_parameters"] = resolved


# ---------------------------------------------------------------------------------------------
# Schema errors -> diagnostics


def _submodel(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        found = _submodel(arg)
        if found is not None:
            return found
    return None


def _model_at(loc: tuple) -> type[BaseModel] | None:
    model: type[BaseModel] | None = Scenario
    for part in loc:
        if isinstance(part, int):
            continue
        if model is None or part not in model.model_fields:
            return None
        model = _submodel(model.model_fields[part].annotation)
    return model


def _where(loc: tuple) -> str:
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _schema_diagnostic(err: Mapping[str, Any], tree: _Tree, diags: Diagnostics) -> None:
    loc = tuple(err["loc"])
    if any(loc[:n] in tree.broken for n in range(1, len(loc) + 1)):
        return  # one message per fault: the unreadable value was already reported
    default = Span(tree.file, 1, 1)
    kind = err["type"]
    if kind == "extra_forbidden":
        key = str(loc[-1])
        model = _model_at(loc[:-1])
        allowed = sorted(model.model_fields) if model else []
        hint = difflib.get_close_matches(key, allowed, n=1)
        message = f"unknown key '{key}'"
        if loc[:-1]:
            message += f" in {_where(loc[:-1])}"
        message += f" (did you mean '{hint[0]}'?)" if hint else (f" (allowed: {', '.join(allowed)})" if allowed else "")
        diags.report("E-SCENARIO", tree.key_spans.get(loc) or _nearest(tree.spans, loc, default), message)
        return
    if kind == "missing":
        where = f" in {_where(loc[:-1])}" if loc[:-1] else ""
        diags.report("E-SCENARIO", _nearest(tree.spans, loc[:-1], default), f"missing required key '{loc[-1]}'{where}")
        return
    message = str(err["msg"]).removeprefix("Value error, ")
    if loc and loc[-1] == "[key]":
        loc = loc[:-1]
        diags.report("E-SCENARIO", tree.key_spans.get(loc) or _nearest(tree.spans, loc, default),
                    f"{_where(loc[:-1])}: bad key {loc[-1]!r}: {message}")
        return
    diags.report("E-SCENARIO", _nearest(tree.spans, loc, default), f"{_where(loc) or 'scenario'}: {message}")


# ---------------------------------------------------------------------------------------------
# Names and values (works on plain data, so it also runs when the schema rejected something else)


def _items(value: Any) -> Iterator[tuple[Any, Any]]:
    return iter(value.items()) if isinstance(value, dict) else iter(())


def _entries(value: Any) -> Iterator[tuple[int, Any]]:
    return enumerate(value) if isinstance(value, list) else iter(())


def _check_names(data: Mapping[str, Any], names: NameTable, spans: Mapping[tuple, Span],
                 key_spans: Mapping[tuple, Span], default: Span, diags: Diagnostics) -> dict[str, OperandRef]:
    refs: dict[str, OperandRef] = {}

    def at(path: tuple) -> Span:
        return _nearest(spans, path, default)

    def resolve(name: Any, path: tuple, key: bool) -> OperandRef | None:
        if not isinstance(name, str):
            return None  # the schema reports names that are not text
        span = (key_spans.get(path) if key else None) or at(path)
        try:
            ref = names.resolve(name)
        except NameProblem as problem:
            diags.report("E-SCENARIO", span, str(problem))
            return None
        refs[name] = ref
        return ref

    def assignments(mapping: Any, path: tuple) -> None:
        for name, value in _items(mapping):
            ref = resolve(name, path + (name,), key=True)
            if ref is not None and (problem := check_value(ref, value)) is not None:
                diags.report("E-SCENARIO", at(path + (name,)), f"{label(name, ref)}: {problem}")

    cycles = data.get("cycles")
    cycles = cycles if isinstance(cycles, int) and not isinstance(cycles, bool) and cycles > 0 else None

    def cycle_in_range(entry: Any, path: tuple, what: str) -> None:
        cycle = entry.get("cycle") if isinstance(entry, dict) else None
        if cycles is not None and isinstance(cycle, int) and not isinstance(cycle, bool) and cycle >= cycles:
            diags.report("E-SCENARIO", at(path + ("cycle",)),
                        f"{what} at cycle {cycle} never happens: the scenario runs cycles 0..{cycles - 1}")

    assignments(data.get("initial"), ("initial",))
    for name, value in _items(data.get("mp_data")):
        path = ("mp_data", name)
        if not isinstance(name, str):
            continue
        ref = names.table_rows.get(name)
        if ref is None:
            near = difflib.get_close_matches(name, list(names.table_rows), n=1)
            hint = f" (did you mean '{near[0]}'?)" if near else ""
            where = "no row of the project's data tables sets it" if names.table_rows else \
                "the project has no data tables (MP_Data.tab, MP_Config.tab)"
            diags.report("E-SCENARIO", key_spans.get(path) or at(path), f"mp_data: unknown row '{name}': {where}{hint}")
        elif (problem := check_value(ref, value)) is not None:
            diags.report("E-SCENARIO", at(path), f"mp_data: {label(name, ref)}: {problem}")
    for i, event in _entries(data.get("events")):
        cycle_in_range(event, ("events", i), "event")
        if isinstance(event, dict):
            assignments(event.get("set"), ("events", i, "set"))
    for i, expectation in _entries(data.get("expect")):
        cycle_in_range(expectation, ("expect", i), "expectation")
        if isinstance(expectation, dict):
            assignments(expectation.get("values"), ("expect", i, "values"))
    random_part = data.get("random")
    if isinstance(random_part, dict):
        for i, pattern in _entries(random_part.get("inputs")):
            path = ("random", "inputs", i)
            if isinstance(pattern, str) and is_glob(pattern):
                continue  # globs are expanded (and warned about) when the stimulus is built
            ref = resolve(pattern, path, key=False)
            if ref is not None and ref.kind not in BIT_KINDS:
                diags.report("E-SCENARIO", at(path), f"{label(pattern, ref)} is not a bit operand and cannot toggle")
            elif ref is not None and pattern in names.non_toggle:
                diags.report("E-SCENARIO-UNUSED", at(path), f"'{pattern}' is an alias or constant and is never toggled")
    for i, pattern in _entries(data.get("observe")):
        if not (isinstance(pattern, str) and is_glob(pattern)):
            resolve(pattern, ("observe", i), key=False)
    return refs


# ---------------------------------------------------------------------------------------------
# Entry points


def load_scenario(path: Path, names: NameTable) -> Scenario:
    """Read, validate and bind a scenario file; raises ScenarioError with every E-SCENARIO problem found."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError([Diagnostic.of("E-SCENARIO", Span(str(path), 1, 1),
                                           f"cannot read scenario file: {exc}")]) from None
    scenario = scenario_from_text(text, str(path), path.parent, names, path.stem)
    scenario._source = path
    return scenario


def scenario_from_text(text: str, file: str, folder: Path, names: NameTable, default_name: str = "scenario"
                       ) -> Scenario:
    """A scenario from YAML text (`file` names it in diagnostics, `folder` is where its relative machine-parameter
    file is looked for); validated and bound like a scenario file, but with no source file."""
    diags = Diagnostics()
    node = _compose(text, file, diags)
    if node is None:
        if not diags.has_errors():
            diags.report("E-SCENARIO", Span(file, 1, 1), "empty scenario file: missing required key 'cycles'")
        raise ScenarioError(diags.items)
    tree = _Tree(file, diags)
    data = tree.build(node)
    if not isinstance(data, dict):
        diags.report("E-SCENARIO", tree.spans[()], "a scenario is a mapping of keys (name, cycles, events, ...)")
        raise ScenarioError(diags.items)
    data.setdefault("name", default_name)
    cycles = data.get("cycles")
    if isinstance(cycles, int) and not isinstance(cycles, bool) and cycles > MAX_CYCLES:
        diags.report("E-SCENARIO", tree.spans[("cycles",)], f"cycles: {_number_text(cycles)} is more than a scenario "
                     f"file may run ({MAX_CYCLES} cycles); split the run into scenarios of fewer cycles")
    _convert_mp(data, tree)
    _resolve_mp_file(data, folder, tree)
    refs = _check_names(data, names, tree.spans, tree.key_spans, Span(file, 1, 1), diags)
    scenario: Scenario | None = None
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as exc:
        for err in exc.errors():
            _schema_diagnostic(err, tree, diags)
    if scenario is None or diags.has_errors():
        raise ScenarioError(diags.items)
    scenario._spans = tree.spans
    scenario._key_spans = tree.key_spans
    scenario._refs = refs
    scenario._warnings = tuple(diags.warnings)
    return scenario


def bind(scenario: Scenario, names: NameTable) -> Scenario:
    """Check the names and values of a scenario built or edited in code; returns a copy bound to `names`."""
    diags = Diagnostics()
    data = scenario.model_dump()
    refs = _check_names(data, names, scenario._spans, scenario._key_spans, scenario._file_span(), diags)
    if diags.has_errors():
        raise ScenarioError(diags.items)
    bound = scenario.model_copy()
    bound._refs = refs
    bound._warnings = tuple(diags.warnings)
    return bound
