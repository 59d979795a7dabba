"""The frame of one routine's symbolic execution: emitted statements, symbolic register state, what the backend provides."""

from __future__ import annotations

import dataclasses
from types import MappingProxyType
from typing import Callable

from transpiler.diagnostics import Span
from transpiler.ir import Op, Operand
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.layout import Layout
from transpiler.backends.st.liveness import REGS

REG_TYPES = MappingProxyType({
    "LA": ("BOOL", "HH_LA", "logic accumulator"), "WA": ("DINT", "HH_WA", "word accumulator"),
    "SA": ("STRING", "HH_SA", "string accumulator"), "X": ("DINT", "HH_X", "index register")})


class Unsupported(Exception):
    """An op the ST backend cannot translate; the routine reports it (at `span`, the op's line) and continues."""

    def __init__(self, message: str, span: Span | None = None):
        super().__init__(message)
        self.span = span


@dataclasses.dataclass
class Frame:
    op: Op
    saved: Expr



class Emitter:
    """Collects the statements of a routine body (stmt.py), with the source comments waiting for the next one.

    `block` is the statement list being filled: `nested` swaps in the list of a compound statement's branch.

    It also knows which accessor instances hold the value of an indexed operand right now (`held_access`): an
    accessor's output Q keeps the operand's value until something could change it, so a second read of the same
    address in straight-line code reuses Q instead of calling the accessor again. Any statement that could write
    the operand space or the index ends that knowledge: every statement but an assignment of a scratch variable
    (`scratch`: registers and temporaries, which hold no operand; it ends only what reads that variable) and the
    accessor calls it is told of."""

    def __init__(self, scratch: Callable[[str], bool] = lambda name: False) -> None:
        self.block: list[S.Stmt] = []
        self.pending_comments: list[str] = []
        self.scratch = scratch
        # accessor instance -> (operand kind, address key, variables the address reads)
        self.access_values: dict[str, tuple[str, AccessKey, frozenset[str]]] = {}

    def comment(self, text: str) -> None:
        self.pending_comments.append(text)

    def flush_comments(self) -> None:
        if self.pending_comments:
            self.block.extend(S.Comment(text) for text in self.pending_comments)
            self.pending_comments = []

    def add(self, stmt: S.Stmt) -> None:
        if self.access_values:
            self._forget_changed(stmt)
        if self.pending_comments:
            self.flush_comments()
        self.block.append(stmt)

    def add_access(self, call: S.Call, kind: str, key: AccessKey, reads: frozenset[str], write: bool) -> None:
        """An accessor call reading (or writing) the operand of `kind` at `key`; afterwards its Q holds that
        operand's value. A write makes every other instance's value of an address it may be stale."""
        self.flush_comments()
        self.block.append(call)
        # The call changes the instance's Q and, writing, one operand of `kind`: addresses that read either change.
        changed = {call.callee.upper()} | ({f"#{kind}"} if write else set())
        self.access_values = {inst: held for inst, held in self.access_values.items()
                              if not changed & held[2] and (not write or held[0] != kind or _distinct(held[1], key))}
        self.access_values.pop(call.callee, None)
        if not changed & reads:
            self.access_values[call.callee] = (kind, key, reads)

    def access_rank(self, kind: str, key: AccessKey) -> Callable[[str], int]:
        """How well an accessor instance suits a call for the operand of `kind` at `key`: best one that holds that
        operand already (a write makes its value stale anyway), then one that holds nothing, last one whose value
        a later read could still reuse."""
        def rank(inst: str) -> int:
            held = self.access_values.get(inst)
            return 1 if held is None else 0 if held[:2] == (kind, key) else 2
        return rank

    def held_access(self, kind: str, key: AccessKey) -> str | None:
        """An accessor instance whose Q holds the operand of `kind` at `key` now, if any."""
        return next((inst for inst, held in self.access_values.items() if held[:2] == (kind, key)), None)

    def _forget_changed(self, stmt: S.Stmt) -> None:
        if not self.access_values or isinstance(stmt, S.Comment):
            return
        target = E.base_name(stmt.target) if isinstance(stmt, S.Assign) else None
        if target is not None and self.scratch(target):
            self.access_values = {inst: held for inst, held in self.access_values.items() if target not in held[2]}
        else:
            self.access_values = {}

    def nested(self, comments_before: bool = True) -> _Branch:
        """Statements added inside go to the list yielded (a branch of the compound statement added after it).

        Comments waiting when it opens go before the compound statement (`comments_before`) or into the branch;
        those waiting when it closes end the branch. A branch may run after other paths (a loop body after its
        own end): it starts knowing no accessor values, and after it none is known either."""
        return _Branch(self, comments_before)


class _Branch:
    """The context of Emitter.nested (a class of its own: a generator-based context manager costs several times
    as much, and the structurer opens one for every branch of every IF)."""

    def __init__(self, emitter: Emitter, comments_before: bool):
        self.emitter = emitter
        self.comments_before = comments_before
        self.saved: list[S.Stmt] = []

    def __enter__(self) -> list[S.Stmt]:
        out = self.emitter
        if self.comments_before:
            out.flush_comments()
        self.saved, out.block = out.block, []
        out.access_values = {}
        return out.block

    def __exit__(self, kind, value, traceback) -> bool:
        out = self.emitter
        if kind is None:
            out.flush_comments()
        out.block = self.saved
        out.access_values = {}
        return False


# The address of an indexed operand as (constant part, text of the variable part, '' when none): two keys with the
# same variable part and different constants never name the same operand.
AccessKey = tuple[int, str]


def _distinct(a: AccessKey, b: AccessKey) -> bool:
    return a[1] == b[1] and a[0] != b[0]


def tag(span: Span) -> str:
    """The note that ties a statement to its source line."""
    return f"{span.file}:{span.line}"


class SymbolicState:
    """Accumulators (None = the value sits in its global register variable), data stack and bracket frames."""

    def __init__(self, gen: "RoutineContext"):
        self.gen = gen
        self.regs: dict[str, Expr | None] = dict.fromkeys(REGS)
        self.stack: list[tuple[str, Expr]] = []
        self.frames: list[Frame] = []
        # (op index, accessor instances that op has read): values its handler may hold outside this state.
        self.held: tuple[int, set[str]] = (-1, set())

    def reg(self, name: str) -> Expr:
        value = self.regs[name]
        if value is not None:
            return value
        return E.var(self.gen.register(name), REG_TYPES[name][0])

    def set(self, name: str, value: Expr) -> None:
        self.regs[name] = value


class AccessorPool:
    """The instances of the accessor FBs one routine calls, per operand kind: HH_M_index, HH_M_index_2, ...

    An indexed read leaves its value in the instance's output Q until the instance is called again; several
    instances let several such values be in flight at once without a temporary (see OperandMixin.bit)."""

    def __init__(self) -> None:
        self.count: dict[str, int] = {}         # kind -> instances handed out so far

    @staticmethod
    def _name(kind: str, n: int) -> str:
        return f"HH_{kind}_index" if n == 1 else f"HH_{kind}_index_{n}"

    def pick(self, kind: str, usable: Callable[[str], bool], rank: Callable[[str], int] = lambda name: 0) -> str:
        """The instance of `kind` that `usable` accepts and `rank` puts first (the first of equal rank); a new one
        when none is usable."""
        existing = [self._name(kind, n) for n in range(1, self.count.get(kind, 0) + 1)]
        candidates = [name for name in existing if usable(name)]
        if candidates:
            return min(candidates, key=rank)
        self.count[kind] = len(existing) + 1
        return self._name(kind, len(existing) + 1)

    def instances(self) -> list[tuple[str, str]]:
        """(kind, instance name) of every instance handed out, in declaration order."""
        return [(kind, self._name(kind, n)) for kind in sorted(self.count) for n in range(1, self.count[kind] + 1)]


class RoutineContext:
    """What the symbolic executor needs from the backend: layout, register names, helper registry, liveness."""

    def __init__(self, layout: Layout, emitter: Emitter, live_after: Callable[[int], frozenset[str]],
                 register: Callable[[str], str], helper: Callable[[str], None], temp: Callable[[str], str],
                 kfield: Callable[[Operand], str], stack_names: Callable[[], tuple[str, str]],
                 module_call: Callable[[int], str], semantics,
                 bit_accessor: Callable[..., str], jobs=None,
                 instance: Callable[[str], str] | None = None):
        self.layout = layout
        self.out = emitter
        self.live_after = live_after
        self.register = register
        self.helper = helper
        self.temp = temp
        self.kfield = kfield
        self.stack_names = stack_names
        self.module_call = module_call
        self.semantics = semantics
        self.bit_accessor = bit_accessor
        self.jobs = jobs                    # jobs.RoutineJobs of this routine (None: SUBM/RPLY/CAN not translated)
        # A local FB instance named after its type (a temporary's name where the backend gives no namer).
        self.instance: Callable[[str], str] = instance or temp
        self.flag_markers = semantics.profile.interface
        self.dialect = layout.dialect       # the target's table: how bits of a word are read



class ExecutorPart:
    """What every part of the executor shares: set by Executor.__init__ (symbolic.py)."""

    ctx: RoutineContext
    s: SymbolicState
    index: int                      # op index being executed (liveness is read after it)
