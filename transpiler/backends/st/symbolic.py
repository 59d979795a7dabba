"""Symbolic execution of one routine's ops: accumulators, data stack and brackets become expressions; stores become ST statements."""

from __future__ import annotations

from types import MappingProxyType
from typing import Callable, Mapping

from transpiler.ir import Op
from transpiler.backends.st.arith import ArithmeticMixin
from transpiler.backends.st.inflight import InFlightMixin
from transpiler.backends.st.operands import OperandMixin
from transpiler.backends.st.ops_bracket import BracketOpsMixin
from transpiler.backends.st.ops_jobs import JobOpsMixin
from transpiler.backends.st.ops_logic import LogicOpsMixin
from transpiler.backends.st.ops_string import StringOpsMixin
from transpiler.backends.st.ops_word import WordOpsMixin
from transpiler.backends.st.routine import RoutineContext, SymbolicState, Unsupported
from transpiler.backends.st.stackops import StackMixin, StaticStack


class Executor(LogicOpsMixin, WordOpsMixin, BracketOpsMixin, StackMixin, StringOpsMixin, JobOpsMixin,
               ArithmeticMixin, OperandMixin, InFlightMixin):
    """Translates straight-line ops; control-flow ops are left to the structurer, which calls the hooks it shares."""

    def __init__(self, ctx: RoutineContext, static: StaticStack | None = None):
        self.ctx = ctx
        self.s = SymbolicState(ctx)
        self.index = 0
        # A routine with a static stack depth starts with its parameters on the symbolic stack (see stackops).
        self.static = static
        # (the depth recorded at each op, looked up before every op: sync_stack)
        self.stack_at = static.interface.stack_at if static is not None else None
        if static is not None:
            self.s.stack = static.initial()

    def run(self, op: Op, index: int) -> None:
        self.index = index
        stack_at = self.stack_at
        # (before most ops no entry is expected and none is held: nothing to bring in line)
        if stack_at is not None and (stack_at.get(index) or self.s.stack):
            self.sync_stack(index)
        for text in op.comments:
            self.ctx.out.comment(text)
        handler = HANDLERS.get(op.code)
        if handler is None:
            raise Unsupported(f"{op.mnemonic} ({op.code})", op.span)
        try:
            handler(self, op)
        except Unsupported as exc:
            exc.span = exc.span or op.span
            raise

    def op_LBL(self, op: Op) -> None:
        pass

    op_NOP = op_LBL
    op_KFIELD = op_LBL


# The handler of each op code (`op_<code>`), looked up once instead of through the mixins on every op.
HANDLERS: Mapping[str, Callable[[Executor, Op], None]] = MappingProxyType(
    {name[3:]: getattr(Executor, name) for name in dir(Executor) if name.startswith("op_")})
