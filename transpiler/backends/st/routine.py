"""The frame of one routine's symbolic execution: emitted statements, symbolic register state, what the backend provides."""

from __future__ import annotations

import contextlib
import dataclasses
from types import MappingProxyType
from typing import Callable, Iterator

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

    `block` is the statement list being filled: `nested` swaps in the list of a compound statement's branch."""

    def __init__(self) -> None:
        self.block: list[S.Stmt] = []
        self.pending_comments: list[str] = []

    def comment(self, text: str) -> None:
        self.pending_comments.append(text)

    def flush_comments(self) -> None:
        self.block.extend(S.Comment(text) for text in self.pending_comments)
        self.pending_comments = []

    def add(self, stmt: S.Stmt) -> None:
        self.flush_comments()
        self.block.append(stmt)

    @contextlib.contextmanager
    def nested(self, comments_before: bool = True) -> Iterator[list[S.Stmt]]:
        """Statements added inside go to the list yielded (a branch of the compound statement added after it).

        Comments waiting when it opens go before the compound statement (`comments_before`) or into the branch;
        those waiting when it closes end the branch."""
        if comments_before:
            self.flush_comments()
        saved, self.block = self.block, []
        inner = self.block
        try:
            yield inner
            self.flush_comments()
        finally:
            self.block = saved


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

    def pick(self, kind: str, usable: Callable[[str], bool]) -> str:
        """The first instance of `kind` that `usable` accepts; a new one when none does."""
        n = 1
        while n <= self.count.get(kind, 0) and not usable(self._name(kind, n)):
            n += 1
        self.count[kind] = max(n, self.count.get(kind, 0))
        return self._name(kind, n)

    def instances(self) -> list[tuple[str, str]]:
        """(kind, instance name) of every instance handed out, in declaration order."""
        return [(kind, self._name(kind, n)) for kind in sorted(self.count) for n in range(1, self.count[kind] + 1)]


class RoutineContext:
    """What the symbolic executor needs from the backend: layout, register names, helper registry, liveness."""

    def __init__(self, layout: Layout, emitter: Emitter, live_after: Callable[[int], frozenset[str]],
                 register: Callable[[str], str], helper: Callable[[str], None], temp: Callable[[str], str],
                 kfield: Callable[[Operand], str], stack_names: Callable[[], tuple[str, str]],
                 module_call: Callable[[int], str], semantics,
                 bit_accessor: Callable[[str, Callable[[str], bool]], str], jobs=None,
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
