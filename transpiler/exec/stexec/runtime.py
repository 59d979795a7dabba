"""Instantiates a compiled ST project and runs it cycle by cycle; reads and writes variables by path."""

from __future__ import annotations

import itertools
import re
import traceback
from typing import Any, Callable, Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.compiler import base_tick
from transpiler.exec.stexec.errors import StError, StRuntimeError, Trap, st_diag
from transpiler.exec.stexec.model import CompiledProject, PouInfo, VarInfo
from transpiler.exec.stexec.pycode import normalise_address, storage_attr
from transpiler.exec.stexec.rtlib import HELPERS, f32, wrap_int
from transpiler.exec.stexec.schema import probe_helpers

_ELEMENT_PATH = re.compile(r"([A-Za-z_][A-Za-z0-9_.]*)\[([0-9]+)\]")
_PATH_TOKEN = re.compile(r"\s*(?:(%[A-Za-z]+[0-9.]*[0-9])|([A-Za-z_][A-Za-z0-9_]*)|\.|\[([^\]]*)\])")


# ====================================================================== value conversion at the boundary
# The converters are chosen from the type once, when a path is first resolved or an external is installed, so
# that get(), set() and every external call run only the checks that apply to that one type.

def to_st_converter(ty: T.Type, what: str) -> Callable[[Any], Any]:
    """The function that takes a Python value from outside (set, externals) to the runtime representation of ty;
    it raises ValueError for a value that does not fit."""
    b = T.base(ty)
    if isinstance(b, T.Elem) and b.cat in ("int", "bit"):
        lo, hi = (ty.lo, ty.hi) if isinstance(ty, T.SubrangeT) else (None, None)

        def integer(value: Any) -> int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise ValueError(f"{what}: {b.name} needs an int, got {value!r}")
            if lo is not None and not lo <= value <= hi:
                raise ValueError(f"{what}: {value} outside the subrange {lo}..{hi}")
            return wrap_int(value, b.bits, b.signed)
        return integer
    if b is T.BOOL:
        def boolean(value: Any) -> bool:
            if isinstance(value, bool):
                return value
            if value in (0, 1) and isinstance(value, int):
                return bool(value)
            raise ValueError(f"{what}: BOOL needs True/False, got {value!r}")
        return boolean
    if isinstance(b, T.Elem) and b.cat == "real":
        def real(value: Any) -> float:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"{what}: {b.name} needs a number, got {value!r}")
            return f32(float(value)) if b is T.REAL else float(value)
        return real
    if b is T.TIME:
        def time(value: Any) -> int:
            if isinstance(value, bool) or not isinstance(value, int):
                raise ValueError(f"{what}: TIME needs int milliseconds, got {value!r}")
            return value
        return time
    if b is T.STRING:
        def string(value: Any) -> str:
            if not isinstance(value, str):
                raise ValueError(f"{what}: STRING needs a str, got {value!r}")
            if len(value) > T.STR_MAX:
                raise ValueError(f"{what}: string of {len(value)} characters, at most {T.STR_MAX}")
            return value
        return string
    if isinstance(b, T.EnumT):
        def enum(value: Any) -> int:
            if isinstance(value, str):
                idx = b.index(value)
                if idx is None:
                    raise ValueError(f"{what}: '{value}' is not a value of {b.name}")
                return idx
            if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < len(b.values):
                return value
            raise ValueError(f"{what}: {b.name} needs one of {', '.join(b.values)}")
        return enum

    def aggregate(value: Any) -> Any:
        raise ValueError(f"{what}: cannot set a whole {ty}; set its elements or fields")
    return aggregate


def from_st_converter(ty: T.Type) -> Callable[[Any], Any]:
    """The function that turns ty's runtime representation into the plain Python value get() returns: enums by
    name, arrays as lists, structs and FB instances as dicts, everything else as it is."""
    b = T.base(ty)
    if isinstance(b, T.EnumT):
        return b.values.__getitem__
    if isinstance(b, T.ArrayT):
        elem = from_st_converter(b.elem)
        return lambda value: [elem(v) for v in value]
    if isinstance(b, (T.StructT, T.FbT)):
        members = b.fields.values() if isinstance(b, T.StructT) else b.pou.state_vars
        fields = [(m.name, "v_" + m.name.lower(), from_st_converter(m.ty)) for m in members]
        return lambda value: {name: convert(getattr(value, attr)) for name, attr, convert in fields}
    return _identity


def _identity(value: Any) -> Any:
    return value


def _external_converter(ty: T.Type, what: str) -> Callable[[Any], Any]:
    """What an external hands back, as the runtime stores it: aggregates are the live objects and pass unchanged,
    scalars are checked like set() and a misfit becomes a Trap (a runtime error of the ST program)."""
    if T.is_aggregate(ty):
        return _identity
    convert = to_st_converter(ty, what)

    def checked(value: Any) -> Any:
        try:
            return convert(value)
        except ValueError as exc:
            raise Trap(str(exc)) from exc
    return checked


# ====================================================================== externals

def _fb_external(fn: Callable, pou: PouInfo) -> Callable:
    fields = [(v.key, "v_" + v.key, _external_converter(v.ty, f"{pou.name}.{v.key}")) for v in pou.state_vars]

    def body(inst: Any) -> None:
        state = {k: getattr(inst, attr) for k, attr, _c in fields}
        try:
            fn(state)
        except (Trap, StRuntimeError):
            raise
        except Exception as exc:  # noqa: BLE001 - reported as a runtime error of the ST program
            raise Trap(f"external implementation of {pou.name} raised {type(exc).__name__}: {exc}") from exc
        for k, attr, convert in fields:
            if k in state:
                setattr(inst, attr, convert(state[k]))
    return body


def _fn_external(fn: Callable, pou: PouInfo) -> Callable:
    params = [v.key for v in pou.pyparams]
    result_of = _external_converter(pou.result, f"result of {pou.name}")
    inout_pos = {v.key: i for i, v in enumerate(pou.pyparams)}
    # what follows the result: (key, converter, position of the in-out's argument or None for an output, type)
    rest = [(v.key, _external_converter(v.ty, f"{pou.name}.{v.key}"),
             inout_pos[v.key] if v.kind == "inout" else None, v.ty) for v in pou.tuple_outputs]

    def call(*args: Any) -> Any:
        try:
            res = fn(**dict(zip(params, args)))
        except (Trap, StRuntimeError):
            raise
        except Exception as exc:  # noqa: BLE001
            raise Trap(f"external implementation of {pou.name} raised {type(exc).__name__}: {exc}") from exc
        outs: dict = {}
        if isinstance(res, tuple):
            if len(res) != 2 or not isinstance(res[1], dict):
                raise Trap(f"external implementation of {pou.name} must return a result or (result, dict)")
            res, outs = res
            outs = {str(k).lower(): v for k, v in outs.items()}
        result = result_of(res)
        if not rest:
            return result
        values = [result]
        for key, convert, pos, ty in rest:
            if key in outs:
                values.append(convert(outs[key]))
            elif pos is not None:
                values.append(args[pos])
            else:
                values.append(T.default_value(ty))
        return tuple(values)
    return call


# ====================================================================== path resolution

class _Ref:
    """A resolved variable path: a holder object plus attribute name, or a list plus index.

    to_py and to_st are the conversions get() and set() apply; _resolve() fills them in once per path."""

    __slots__ = ("holder", "attr", "index", "ty", "constant", "to_py", "to_st")

    def __init__(self, holder: Any, attr: Optional[str], index: Optional[int], ty: T.Type, constant: bool):
        self.holder, self.attr, self.index, self.ty, self.constant = holder, attr, index, ty, constant
        self.to_py: Callable[[Any], Any] = _identity
        self.to_st: Callable[[Any], Any] = _identity

    def get(self) -> Any:
        if self.attr is not None:
            return getattr(self.holder, self.attr)
        return self.holder[self.index]

    def set(self, value: Any) -> None:
        if self.attr is not None:
            setattr(self.holder, self.attr, value)
        else:
            self.holder[self.index] = value


class Runtime:
    """One running instance of the project's configuration (see the package docstring for the contract)."""

    def __init__(self, project: CompiledProject, externals: Optional[dict[str, Callable]], mutant: int = 0):
        self._project = project
        self.infected: set[int] = set()      # mutations a PROBE run found infected (schema.py)
        if not project.has_configuration or not project.programs:
            raise StError([st_diag(Span(project.filename, 1, 1),
                                   "the file has no CONFIGURATION with a program instance to run")])
        ns: dict[str, Any] = dict(HELPERS, _LOOP_RANGE=range(project.loop_limit), _MUT=mutant,
                                  **probe_helpers(self.infected))
        exec(project.code, ns)   # noqa: S102 - code generated by our own compiler from checked ST
        for name, fn in (externals or {}).items():
            pou = project.pous.get(name.lower())
            if pou is None:
                raise StError([st_diag(Span(project.filename, 1, 1),
                                       f"external implementation for '{name}', which the ST file does not declare")])
            if pou.kind == "function":
                ns["F_" + pou.key] = _fn_external(fn, pou)
            else:
                ns["B_" + pou.key] = _fb_external(fn, pou)
        self._ns = ns
        self._g = ns["C__G"]()
        ns["G"] = self._g
        self._instances: dict[str, tuple[Any, PouInfo, str]] = {}
        self._schedule: list[tuple[int, Callable, Any]] = []
        self.cycle_time_ms = base_tick(project.tasks)
        for p in project.programs:
            inst = ns["C_" + p.pou.key]()
            self._instances[p.name.lower()] = (inst, p.pou, p.name)
            period = p.task.interval_ms // self.cycle_time_ms if p.task is not None else 1
            self._schedule.append((period, ns["B_" + p.pou.key], inst))
        self._tick = 0
        self._refs: dict[str, _Ref] = {}

    # ------------------------------------------------------------------ running
    @property
    def cycle(self) -> int:
        """Number of completed cycles."""
        return self._tick

    @property
    def now_ms(self) -> int:
        """Simulated time of the next cycle (CURRENT_TIME as timers will read it)."""
        return self._tick * self.cycle_time_ms

    def run_cycle(self) -> None:
        tick = self._tick
        self._g.now = tick * self.cycle_time_ms
        try:
            for period, body, inst in self._schedule:
                if tick % period == 0:
                    body(inst)
        except StRuntimeError:
            raise
        except Exception as exc:   # noqa: BLE001 - every fault inside generated code becomes StRuntimeError
            raise self._runtime_error(exc) from None
        self._tick = tick + 1

    def _runtime_error(self, exc: BaseException) -> StRuntimeError:
        span = None
        filename = f"<stexec:{self._project.filename}>"
        for frame, lineno in traceback.walk_tb(exc.__traceback__):
            if frame.f_code.co_filename == filename:
                spans = self._project.line_spans
                if 0 < lineno < len(spans) and spans[lineno] is not None:
                    span = spans[lineno]
        if isinstance(exc, Trap):
            message = exc.message
        elif isinstance(exc, ZeroDivisionError):
            message = "division by zero"
        elif isinstance(exc, RecursionError):
            message = "call nesting too deep"
        elif isinstance(exc, ValueError) and "negative shift count" in str(exc):
            message = "negative shift count"
        else:
            message = f"internal error of the built-in executor: {type(exc).__name__}: {exc}"
        return StRuntimeError(message, span)

    # ------------------------------------------------------------------ addressing
    def _resolve(self, path: str) -> _Ref:
        ref = self._refs.get(path)
        if ref is not None:
            return ref
        ref = self._resolve_uncached(path)
        ref.to_py = from_st_converter(ref.ty)
        if ref.constant:
            ref.to_st = _refusal(f"'{path}' is a CONSTANT")
        elif T.is_aggregate(ref.ty):
            ref.to_st = _refusal(f"'{path}' is a {ref.ty}; set its elements or fields one by one")
        else:
            ref.to_st = to_st_converter(ref.ty, path)
        self._refs[path] = ref
        return ref

    def _tokens(self, path: str) -> list[tuple[str, str]]:
        out, pos = [], 0
        while pos < len(path):
            m = _PATH_TOKEN.match(path, pos)
            if not m or m.end() == pos:
                raise KeyError(f"malformed variable path '{path}'")
            if m.group(1):
                out.append(("addr", m.group(1)))
            elif m.group(2):
                out.append(("name", m.group(2)))
            elif m.group(3) is not None:
                out.append(("index", m.group(3)))
            else:
                out.append(("dot", "."))
            pos = m.end()
        return out

    def _resolve_uncached(self, path: str) -> _Ref:
        element = _ELEMENT_PATH.fullmatch(path)
        if element is not None:
            # `A[5]`, `inst.A[5]`: the array's reference is cached, so a sweep over all elements of an array
            # resolves its name once.
            return self._element(self._resolve(element.group(1)), element.group(2), path)
        toks = self._tokens(path)
        if not toks:
            raise KeyError(path)
        kind, text = toks[0]
        rest = toks[1:]
        if kind == "addr":
            addr = normalise_address(text)
            loc = self._project.locations.get(addr) if addr else None
            if loc is None:
                raise KeyError(f"no variable is located at '{text}'")
            ref = _Ref(self._g, loc[1], None, loc[0], False)
        elif kind == "name":
            key = text.lower()
            g = self._project.globals.get(key)
            if g is not None:
                ref = self._var_ref(self._g, g)
            elif key in self._instances:
                inst, pou, name = self._instances[key]
                if not rest:
                    raise KeyError(f"'{path}' is a program instance; name one of its variables")
                if rest[0][0] != "dot" or len(rest) < 2 or rest[1][0] != "name":
                    raise KeyError(f"malformed variable path '{path}'")
                ref = self._member(inst, pou, rest[1][1], path)
                rest = rest[2:]
            else:
                raise KeyError(f"unknown variable '{text}'")
        else:
            raise KeyError(f"malformed variable path '{path}'")
        while rest:
            kind, text = rest[0]
            if kind == "dot" and len(rest) > 1 and rest[1][0] == "name":
                ref = self._field(ref, rest[1][1], path)
                rest = rest[2:]
            elif kind == "index":
                ref = self._element(ref, text, path)
                rest = rest[1:]
            else:
                raise KeyError(f"malformed variable path '{path}'")
        return ref

    def _var_ref(self, holder: Any, v: VarInfo) -> _Ref:
        if v.location is not None:
            holder = self._g        # every located variable is a cell of its address, stored with the globals
        return _Ref(holder, storage_attr(v), None, v.ty, v.constant)

    def _member(self, inst: Any, pou: PouInfo, name: str, path: str) -> _Ref:
        v = pou.vars.get(name.lower())
        if v is None or v.kind in ("temp", "result"):
            raise KeyError(f"'{path}': {pou.name} has no variable '{name}'")
        if v.kind == "external":
            return self._var_ref(self._g, self._project.globals[v.key])
        return self._var_ref(inst, v)

    def _field(self, ref: _Ref, name: str, path: str) -> _Ref:
        b = T.base(ref.ty)
        obj = ref.get()
        if isinstance(b, T.StructT):
            f = b.fields.get(name.lower())
            if f is None:
                raise KeyError(f"'{path}': {b.name} has no field '{name}'")
            return _Ref(obj, "v_" + name.lower(), None, f.ty, ref.constant)
        if isinstance(b, T.FbT):
            return self._member(obj, b.pou, name, path)
        raise KeyError(f"'{path}': {ref.ty} has no fields")

    def _element(self, ref: _Ref, text: str, path: str) -> _Ref:
        b = T.base(ref.ty)
        if not isinstance(b, T.ArrayT):
            raise KeyError(f"'{path}': {ref.ty} is not an array")
        try:
            idx = [int(part) for part in text.split(",")]
        except ValueError:
            raise KeyError(f"'{path}': array indexes must be integers") from None
        if len(idx) != len(b.dims):
            raise KeyError(f"'{path}': {len(b.dims)} index(es) expected")
        flat = 0
        for i, (lo, hi), stride in zip(idx, b.dims, b.strides()):
            if not lo <= i <= hi:
                raise KeyError(f"'{path}': index {i} outside {lo}..{hi}")
            flat += (i - lo) * stride
        return _Ref(ref.get(), None, flat, b.elem, ref.constant)

    def get(self, path: str) -> Any:
        ref = self._resolve(path)
        return ref.to_py(ref.get())

    def set(self, path: str, value: Any) -> None:
        ref = self._resolve(path)
        ref.set(ref.to_st(value))

    def values(self, paths: list[str]) -> list:
        """get(path) of every path, read once: the elements of a one-dimensional array are taken from the array
        itself, so reading all elements of large arrays resolves each array once instead of every element."""
        arrays: dict[str, tuple[Any, int, int, Callable[[Any], Any]] | None] = {}
        out = []
        for path in paths:
            element = _ELEMENT_PATH.fullmatch(path)
            if element is not None:
                name = element.group(1)
                if name not in arrays:
                    ref = self._resolve(name)
                    b = T.base(ref.ty)
                    one_dim = isinstance(b, T.ArrayT) and len(b.dims) == 1
                    arrays[name] = (ref.get(), *b.dims[0], from_st_converter(b.elem)) if one_dim else None
                array = arrays[name]
                index = int(element.group(2))
                if array is not None and array[1] <= index <= array[2]:
                    out.append(array[3](array[0][index - array[1]]))
                    continue
            out.append(self.get(path))
        return out

    def reader(self, paths: list[str]) -> Callable[[], list]:
        """A function returning get(path) for every path, in order, in one call: the paths are resolved once and
        read by generated code (a co-simulation reads hundreds of variables every cycle). The holders stay valid
        for this runtime's life, as the cached references of get() do."""
        env, items = self.read_expressions(paths)
        exec(compile("def read():\n    return [" + ", ".join(items) + "]\n", "<stexec-reader>", "exec"), env)
        return env["read"]

    def read_expressions(self, paths: list[str]) -> tuple[dict[str, Any], list[str]]:
        """(names, expressions): a Python expression per path that gives get(path) when evaluated with the names,
        for readers that a caller generates around them (reader, or one that converts the values as it reads)."""
        env: dict[str, Any] = {"getattr": getattr}
        items = []
        for i, path in enumerate(paths):
            ref = self._resolve(path)
            env[f"h{i}"] = ref.holder
            if ref.attr is None:
                item = f"h{i}[{ref.index}]"
            elif ref.attr.isidentifier():
                item = f"h{i}.{ref.attr}"
            else:
                item = f"getattr(h{i}, {ref.attr!r})"
            if ref.to_py is not _identity:
                env[f"c{i}"] = ref.to_py
                item = f"c{i}({item})"
            items.append(item)
        return env, items

    def names(self) -> list[str]:
        out: list[str] = []
        for g in self._project.globals.values():
            if g.location is None or g.name and not g.name.startswith("AT "):
                self._leaf_names(g.name, g.ty, out)
        for inst, pou, name in self._instances.values():
            for v in pou.vars.values():
                if v.kind in ("temp", "result", "external") or v.name.startswith("AT "):
                    continue
                self._leaf_names(f"{name}.{v.name}", v.ty, out)
        out.extend(sorted(self._project.locations))
        return out

    def _leaf_names(self, prefix: str, ty: T.Type, out: list[str]) -> None:
        b = T.base(ty)
        if isinstance(b, T.ArrayT):
            for idx in itertools.product(*(range(lo, hi + 1) for lo, hi in b.dims)):
                self._leaf_names(f"{prefix}[{','.join(map(str, idx))}]", b.elem, out)
        elif isinstance(b, T.StructT):
            for f in b.fields.values():
                self._leaf_names(f"{prefix}.{f.name}", f.ty, out)
        elif isinstance(b, T.FbT):
            for v in b.pou.state_vars:
                self._leaf_names(f"{prefix}.{v.name}", v.ty, out)
        else:
            out.append(prefix)


def _refusal(message: str) -> Callable[[Any], Any]:
    def refuse(value: Any) -> Any:
        raise ValueError(message)
    return refuse

