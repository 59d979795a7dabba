"""Subprogram interfaces from the data stack: which routines take parameters and give results through PS/PL in a
fixed number and order, so that the ST can pass them as VAR_INPUT / VAR_OUTPUT instead of emulating the stack.

The analysis is an abstract interpretation of every routine over all its paths. The abstract stack of a routine
is relative to its entry: `u` entries of the caller's stack pulled (the parameters, p0 = the top one) and the
entries pushed since, each a kind ("bit": one word, bit 7; "val": a 32-bit value, two words) or a parameter still
in place. A routine has a static stack effect when every op is reached with one abstract stack on all paths, every
pull finds the kind it expects, and every exit leaves the same stack. It gets an interface when, in addition, every
call site is an unconditional CM (a conditional call, a CASE entry, a fall-through or a submitted job would have to
pass the operands through the real stack). A routine that calls one whose effect is not static is not static
either; the reason is kept for the report. The result serves any caller that knows its callee's effect: a PLC
module can join by giving `module_effect` its parameters and results.
"""

from __future__ import annotations

import bisect
import dataclasses
import re
from types import MappingProxyType
from typing import Callable, Mapping

from transpiler.diagnostics import Span
from transpiler.ir import CallTarget, FileCode, Op, Program
from transpiler.frontend.flow import RoutineBodies
from transpiler.records import quick_init

BIT, VAL = "bit", "val"
WORDS = MappingProxyType({BIT: 1, VAL: 2})
_PUSH = MappingProxyType({"PSW": VAL, "PSL": BIT, "PSX": VAL})
_PULL = MappingProxyType({"PLW": VAL, "PLL": BIT, "PLX": VAL})
_CALLS = ("CALL", "CALLT", "CALLF")
_JOBS = ("SUBM", "RPLY", "CAN")
MAIN = (0, 0)
# The op codes _step looks at; every other op leaves the stack state as it is.
_STACK_CODES = frozenset({"PUSH", "POP", "CASE", *_PUSH, *_PULL, *_CALLS})
_ENDS = frozenset({"EM", "EMT", "EMF"})
# The ops _irregular_call_sites looks at (besides the entries of other routines).
_ENTERING = frozenset({"CALLT", "CALLF", "CASE", *_JOBS})


@quick_init
@dataclasses.dataclass(frozen=True)
class Effect:
    """Static stack effect: parameter kinds (p0 = top of the caller's stack first) and result kinds (bottom first)."""

    params: tuple[str, ...]
    results: tuple[str, ...]
    max_words: int                   # deepest the routine (and its callees) goes above the floor left by its params

    @property
    def empty(self) -> bool:
        return not self.params and not self.results


@quick_init
@dataclasses.dataclass(frozen=True)
class StackInterface:
    """The VAR_INPUT / VAR_OUTPUT of a routine: (name, kind), parameters in the caller's push order, results in
    push order (the caller pulls the last one first); `stack_at` gives, per op index, the kinds of the entries
    above the routine's floor (parameters included), bottom first."""

    params: tuple[tuple[str, str], ...]
    results: tuple[tuple[str, str], ...]
    stack_at: Mapping[int, tuple[str, ...]]

    @property
    def empty(self) -> bool:
        return not self.params and not self.results


@dataclasses.dataclass(frozen=True)
class Dynamic:
    """Why a routine keeps the emulated data stack."""

    reason: str
    span: Span


class _NotStatic(Exception):
    def __init__(self, reason: str, span: Span):
        super().__init__(reason)
        self.reason = reason
        self.span = span


@dataclasses.dataclass
class _Walk:
    """The abstract state of one routine: `u` parameters pulled, `items` pushed since (kinds or ('p', k))."""

    params: dict[int, str]
    states: dict[int, tuple[int, tuple]]
    max_u: int = 0
    max_words: int = 0


def _lift(state: tuple[int, tuple], u: int) -> tuple:
    """The state written over `u` pulled parameters: the ones it left in place come first, as ('p', k)."""
    have, items = state
    return tuple(("p", k) for k in range(u - 1, have - 1, -1)) + items


class StackAnalysis:
    """Effect and interface of every routine of `program` (keys as CallTarget.key; the main program is (0, 0))."""

    def __init__(self, program: Program, module_effect: Callable[[int], Effect | None] = lambda number: None,
                 capacity_words: int | None = None, bodies: RoutineBodies | None = None):
        self.program = program
        self.bodies = bodies or RoutineBodies.of(program)
        self.module_effect = module_effect
        self.capacity = capacity_words if capacity_words is not None else int(program.semantics["data_stack_words"])
        self.effects: dict[tuple[int, int], Effect] = {}
        self.dynamic: dict[tuple[int, int], Dynamic] = {}
        self._walks: dict[tuple[int, int], _Walk] = {}
        self._active: set[tuple[int, int]] = set()
        self._entries: dict[tuple[int, int], CallTarget] = {r.key: r for r in program.routines}
        self._entries[MAIN] = CallTarget(0, 0, "<main>")
        self._by_file: dict[int, dict[int, CallTarget]] = {}
        for r in program.routines:
            self._by_file.setdefault(r.file, {})[r.index] = r
        self.interfaces: dict[tuple[int, int], StackInterface] = {}
        # file -> indices of its ops in _STACK_CODES, and of those that may enter a routine other than by CM or
        # start one, in order (see _scan)
        self._scanned: dict[int, tuple[list[int], list[int]]] = {}
        self._starts: dict[int, list[int]] = {}        # file -> indices of its routine entries, in order
        self._run()

    # ---- driver

    def _run(self) -> None:
        # A routine whose callers cannot pass operands as parameters has no interface; then its callers must use
        # the real stack too, so repeat until nothing changes.
        excluded: dict[tuple[int, int], Dynamic] = {}
        while True:
            self.effects.clear()
            self.dynamic = dict(excluded)
            self._walks.clear()
            for key in self._entries:
                self._effect(key)
            bad = self._irregular_call_sites()
            new = {k: v for k, v in bad.items() if k not in excluded}
            if not new:
                break
            excluded.update(new)
        for key, effect in self.effects.items():
            walk = self._walks[key]
            u = len(effect.params)
            # (most ops of a routine share one state: each distinct one is worked out once)
            kinds = {s: tuple(self._kind(walk, x) for x in _lift(s, u)) for s in set(walk.states.values())}
            if len(kinds) == 1:     # (most routines: one state at every op)
                stack_at = dict.fromkeys(walk.states, *kinds.values())
            else:
                stack_at = dict(zip(walk.states, map(kinds.__getitem__, walk.states.values())))
            self.interfaces[key] = StackInterface(
                tuple(zip(self._param_names(key, u), reversed(effect.params))),
                tuple(zip(self._result_names(key, effect), effect.results)), MappingProxyType(stack_at))

    @staticmethod
    def _kind(walk: _Walk, item) -> str:
        return walk.params.get(item[1], VAL) if isinstance(item, tuple) else item

    def _irregular_call_sites(self) -> dict[tuple[int, int], Dynamic]:
        """Routines with a non-empty effect that are entered other than by an unconditional CM."""
        bad: dict[tuple[int, int], Dynamic] = {}

        def mark(target: CallTarget | None, how: str, op: Op) -> None:
            if target is None or target.is_module or target.key not in self.effects:
                return
            if not self.effects[target.key].empty and target.key not in bad:
                bad[target.key] = Dynamic(f"{how} at {op.span.file}:{op.span.line}, so its operands stay on the "
                                          "data stack", op.span)

        # Per file, the ops that may enter a routine other than by CM, in order: each routine looks only at those
        # of its body (the bodies cover every op; most ops are none of these).
        for key, entry in self._entries.items():
            file = self.program.files[entry.file]
            body = self.bodies(entry)
            if not body:
                continue
            candidates = self._scan(entry.file)[1]
            inside = set(body)
            for i in candidates[bisect.bisect_left(candidates, body[0]):bisect.bisect_right(candidates, body[-1])]:
                if i not in inside:
                    continue
                op = file.ops[i]
                if op.code in ("CALLT", "CALLF"):
                    mark(op.call, "called conditionally", op)
                elif op.code == "CASE":
                    for t in op.case_targets:
                        mark(t, "called from a CASE table", op)
                elif op.code in _JOBS:
                    mark(op.call, "submitted as a job", op)
                elif key != MAIN and i != entry.index and i in self._by_file.get(entry.file, {}):
                    mark(self._by_file[key[0]][i], "entered by falling through", op)
        return bad

    def _effect(self, key: tuple[int, int]) -> Effect | None:
        if key in self.effects:
            return self.effects[key]
        if key in self.dynamic:
            return None
        entry = self._entries[key]
        file = self.program.files[entry.file]
        if key in self._active:
            raise _NotStatic(f"recursive call of {entry.label}", file.ops[entry.index].span)
        self._active.add(key)
        try:
            effect = self._walk(key, entry, file)
            if key == MAIN and effect.params:
                raise _NotStatic("the main program pulls more than it pushed", file.ops[0].span if file.ops else Span(file.path, 1))
            if effect.max_words + 2 * len(effect.params) > self.capacity:
                raise _NotStatic(f"may need more than the {self.capacity} words of the data stack",
                                 file.ops[entry.index].span)
            self.effects[key] = effect
            return effect
        except _NotStatic as exc:
            self.dynamic[key] = Dynamic(exc.reason, exc.span)
            return None
        finally:
            self._active.discard(key)

    # ---- one routine

    def _walk(self, key: tuple[int, int], entry: CallTarget, file: FileCode) -> Effect:
        # Kept whole (~60 lines): one worklist over the ops; each op's stack effect is a few lines of the same loop.
        walk = _Walk({}, {})
        self._walks[key] = walk
        ordered = self.bodies(entry)
        body = set(ordered)
        if self._leaves_stack_alone(key, entry, ordered, body):
            # (most routines: the walk would reach every op of the body with the empty stack and change nothing)
            walk.states.update(dict.fromkeys(ordered, (0, ())))
            return Effect((), (), 0)
        others = {i for i in self._by_file.get(entry.file, {}) if i != entry.index} if key != MAIN else set()
        exits: list[tuple[int, tuple]] = []
        ops, states = file.ops, walk.states
        n = len(ops)
        todo = [(entry.index, (0, ()))]
        while todo:
            i, state = todo.pop()
            # One path at a time: the next op or a JP's target directly, a conditional jump's target waits in
            # `todo` (the order in which a stack of (op, state) pairs would take them: the newest first).
            while i < n and i in body:
                known = states.get(i)
                if known is not None:
                    u = max(known[0], state[0])
                    if _lift(known, u) != _lift(state, u):
                        raise _NotStatic(f"the data stack holds different entries at line {ops[i].span.line} "
                                         "depending on the path", ops[i].span)
                    break
                states[i] = state
                op = ops[i]
                code = op.code
                if i in others:
                    # Falling through into another routine: its code runs, then this routine ends.
                    state = self._call(walk, state, self._by_file[entry.file][i], op, conditional=False)
                    exits.append((i, state))
                    break
                if code in _STACK_CODES:
                    state = self._step(walk, state, op)
                if code in _ENDS:
                    exits.append((i, state))
                    if code == "EM":
                        break
                if code == "JP":
                    i = op.target
                    continue
                if (code == "JPT" or code == "JPF") and op.target is not None:
                    todo.append((op.target, state))
                i += 1
        u = walk.max_u
        shapes = {_lift(s, u) for _, s in exits}
        if len(shapes) > 1:
            line = file.ops[exits[-1][0]].span
            raise _NotStatic("the routine leaves the data stack with different entries on different paths", line)
        results = tuple(self._kind(walk, x) for x in (shapes.pop() if shapes else ()))
        params = tuple(walk.params.get(k, VAL) for k in range(u))
        return Effect(params, results, walk.max_words)

    def _leaves_stack_alone(self, key: tuple[int, int], entry: CallTarget, ordered: tuple[int, ...],
                            body: set[int]) -> bool:
        """No op of the body (`ordered`, sorted; `body`, the same as a set) touches the data stack, and outside the
        main program none is another routine's entry (where the walk calls that routine and stops)."""
        if not ordered:
            return True
        lo, hi = ordered[0], ordered[-1]
        stack_ops = self._scan(entry.file)[0]
        if any(i in body for i in stack_ops[bisect.bisect_left(stack_ops, lo):bisect.bisect_right(stack_ops, hi)]):
            return False
        if key == MAIN:
            return True
        starts = self._starts.get(entry.file)
        if starts is None:
            starts = self._starts[entry.file] = sorted(self._by_file.get(entry.file, {}))
        return not any(i in body and i != entry.index
                       for i in starts[bisect.bisect_left(starts, lo):bisect.bisect_right(starts, hi)])

    def _scan(self, file_index: int) -> tuple[list[int], list[int]]:
        """The indices of the file's ops in _STACK_CODES and of those in _ENTERING or at a routine's entry, in order
        (one pass over the file's ops for both, the first time a routine of the file asks)."""
        known = self._scanned.get(file_index)
        if known is None:
            starts = self._by_file.get(file_index, {})
            stack_ops: list[int] = []
            entering: list[int] = []
            for i, op in enumerate(self.program.files[file_index].ops):
                code = op.code
                if code in _STACK_CODES:
                    stack_ops.append(i)
                if code in _ENTERING or i in starts:
                    entering.append(i)
            known = self._scanned[file_index] = (stack_ops, entering)
        return known

    def _step(self, walk: _Walk, state: tuple[int, tuple], op: Op) -> tuple[int, tuple]:
        code = op.code
        if code == "PUSH" or code in _PUSH:
            kind = _PUSH.get(code) or (BIT if op.operand.is_bit else VAL)
            return self._push(walk, state, (kind,))
        if code == "POP" or code in _PULL:
            kind = _PULL.get(code) or (BIT if op.operand.is_bit else VAL)
            return self._pull(walk, state, (kind,), op)
        if code in _CALLS:
            if op.call is None:
                raise _NotStatic("unresolved call", op.span)
            return self._call(walk, state, op.call, op, conditional=code != "CALL")
        if code == "CASE":
            for t in op.case_targets:
                self._call(walk, state, t, op, conditional=True)
            return state
        return state        # SUBM, RPLY and CAN do not touch the data stack

    def _call(self, walk: _Walk, state, target: CallTarget, op: Op, conditional: bool):
        if target.is_module:
            effect = self.module_effect(target.module)
            what = f"PLC module {target.module}"
            if effect is None:
                raise _NotStatic(f"{what} at line {op.span.line}: its data stack use is not modelled", op.span)
        else:
            effect = self._effect(target.key)
            what = target.label
            if effect is None:
                raise _NotStatic(f"calls {what} (line {op.span.line}), which keeps the data stack", op.span)
        if conditional and not effect.empty:
            raise _NotStatic(f"calls {what} conditionally (line {op.span.line}) and it moves the data stack", op.span)
        after = self._pull(walk, state, effect.params, op)
        self._note_depth(walk, after, effect.max_words)
        return self._push(walk, after, effect.results)

    def _push(self, walk: _Walk, state, kinds: tuple[str, ...]):
        u, items = state
        state = (u, items + kinds)
        self._note_depth(walk, state, 0)
        return state

    def _note_depth(self, walk: _Walk, state, extra: int) -> None:
        words = sum(WORDS[self._kind(walk, x)] for x in state[1]) + extra
        walk.max_words = max(walk.max_words, words)

    def _pull(self, walk: _Walk, state, kinds: tuple[str, ...], op: Op):
        u, items = state
        for kind in kinds:
            if items:
                top, items = items[-1], items[:-1]
                have = self._kind(walk, top) if not isinstance(top, tuple) or top[1] in walk.params else kind
                if isinstance(top, tuple):
                    walk.params.setdefault(top[1], kind)
            else:
                have = walk.params.setdefault(u, kind)
                u += 1
                walk.max_u = max(walk.max_u, u)
            if have != kind:
                raise _NotStatic(f"line {op.span.line} pulls a {kind} where a {have} was pushed", op.span)
        return (u, items)

    # ---- names

    def _operand_names(self, key: tuple[int, int], codes: tuple[str, ...]) -> list[str | None]:
        entry = self._entries[key]
        file = self.program.files[entry.file]
        walk = self._walks[key]
        return [_word(op) for i in sorted(walk.states) for op in [file.ops[i]] if op.code in codes]

    def _param_names(self, key: tuple[int, int], u: int) -> list[str]:
        """Parameter names (caller's push order) after the operands the routine pulls them into."""
        if not u:
            return []
        pulled = self._operand_names(key, ("POP", "PLW", "PLL", "PLX"))[:u]
        pulled += [None] * (u - len(pulled))
        names = _unique(_strip_common(pulled), "in")
        return list(reversed(names))

    def _result_names(self, key: tuple[int, int], effect: Effect) -> list[str]:
        m = len(effect.results)
        if not m:
            return []
        pushed = self._operand_names(key, ("PUSH", "PSW", "PSL", "PSX"))
        tail = pushed[-m:] if m and len(pushed) >= m else [None] * m
        return _unique(_strip_common(tail), "out")


def _word(op: Op) -> str | None:
    if op.code in ("PSW", "PLW"):
        return "word"
    if op.code in ("PSL", "PLL"):
        return "logic"
    if op.code in ("PSX", "PLX"):
        return "index"
    return op.operand.symbol if op.operand is not None and op.operand.symbol else None


def _strip_common(names: list[str | None]) -> list[str | None]:
    """`ML_ax_inpos`, `ML_ax_clamp_start` -> `inpos`, `clamp_start`: the shared underscore-ended prefix goes."""
    real = [n for n in names if n]
    if len(real) < 2:
        return [re.sub(r"^[A-Z]{1,3}_", "", n) if n else None for n in names]
    prefix = real[0]
    for n in real[1:]:
        while not n.startswith(prefix):
            prefix = prefix[:-1]
    prefix = prefix[:prefix.rfind("_") + 1] if "_" in prefix else ""
    return [n[len(prefix):] if n and len(n) > len(prefix) else n for n in names]


def _unique(names: list[str | None], fallback: str) -> list[str]:
    out: list[str] = []
    for k, n in enumerate(names, start=1):
        name = re.sub(r"[^A-Za-z0-9_]", "_", n) if n else f"{fallback}{k}"
        if not name[0].isalpha():
            name = f"{fallback}_{name}"
        while name.upper() in {o.upper() for o in out}:
            name = f"{name}_{k}"
        out.append(name)
    return out
