"""The data stack: pushes stay symbolic until a boundary, then go to the stack array as 16-bit words; pops read it back.

In a routine whose stack depth the analysis of `interfaces` proved static, nothing goes to the stack array: at a
boundary each entry goes to the variable of its depth (`StaticStack.slot`: a VAR_OUTPUT where the routine's
results end up, else a local), the parameters arrive as VAR_INPUT, and a call of a routine with an interface
passes the entries it pulls as inputs and pushes its outputs.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.interfaces import StackInterface
from transpiler.backends.st.liveness import REGS
from transpiler.backends.st.routine import ExecutorPart, Unsupported

SLOT_TYPES = {"bit": "BOOL", "val": "DINT"}


@dataclasses.dataclass
class StaticStack:
    """The stack of a routine with a static depth: its interface, final names, and where each depth is kept."""

    interface: StackInterface
    params: tuple[str, ...]          # VAR_INPUT names, in the interface's order (caller's push order)
    results: tuple[str, ...]         # VAR_OUTPUT names, bottom first
    local: Callable[[int, str], str]  # (depth, kind) -> a local variable of the routine for that depth

    def slot(self, depth: int, kind: str) -> str:
        results = self.interface.results
        if depth < len(results) and results[depth][1] == kind:
            return self.results[depth]
        return self.local(depth, kind)

    def initial(self) -> list[tuple[str, Expr]]:
        return [(kind, E.var(name, SLOT_TYPES[kind])) for name, (_, kind) in zip(self.params, self.interface.params)]


class StackMixin(ExecutorPart):
    """PS/PL of bits, words and the index register over the symbolic stack and the real one."""

    def _real_push(self, kind: str, value: Expr) -> None:
        stack, sp = self.ctx.stack_names()
        out = self.ctx.out
        pointer = E.var(sp, "INT")
        if kind == "bit":
            if not self.ctx.dialect.bit_access:
                self.ctx.helper("HH_BIT")       # the pop reads the entry's bit with it
            word = E.call("BOOL_TO_INT", [value], "INT", 0, 1)
            out.add(S.Assign(f"{stack}[{sp}]", E.binop("*", word, E.int_const(128, "INT"), "INT", E.PREC_MUL, 0, 128)))
            out.add(S.Assign(sp, E.binop("+", pointer, E.int_const(1, "INT"), "INT", E.PREC_ADD)))
            return
        v = self._stable(E.to_dint(value))
        self.ctx.helper("HH_LOWORD")
        self.ctx.helper("HH_HIWORD")
        out.add(S.Assign(f"{stack}[{sp}]", E.call("HH_LOWORD", [v], "INT")))
        out.add(S.Assign(f"{stack}[{sp} + 1]", E.call("HH_HIWORD", [v], "INT")))
        out.add(S.Assign(sp, E.binop("+", pointer, E.int_const(2, "INT"), "INT", E.PREC_ADD)))

    static: StaticStack | None = None
    stack_at: Mapping[int, tuple[str, ...]] | None = None     # static.interface.stack_at

    def _pop(self, kind: str) -> Expr:
        if self.s.stack and self.s.stack[-1][0] == kind:
            return self.s.stack.pop()[1]
        if self.static is not None:
            raise Unsupported(f"internal: the stack analysis expected a {kind} on the data stack here")
        self.flush_stack()
        stack, sp = self.ctx.stack_names()
        out = self.ctx.out
        pointer = E.var(sp, "INT")
        if kind == "bit":
            out.add(S.Assign(sp, E.binop("-", pointer, E.int_const(1, "INT"), "INT", E.PREC_ADD)))
            entry = E.Expr(f"{stack}[{sp}]", "INT", frozenset([E.base_name(stack), E.base_name(sp)]))
            value = self._bit_of(entry, 7)
        else:
            self.ctx.helper("HH_FROMWORDS")
            out.add(S.Assign(sp, E.binop("-", pointer, E.int_const(2, "INT"), "INT", E.PREC_ADD)))
            value = E.Expr(f"HH_FROMWORDS({stack}[{sp} + 1], {stack}[{sp}])", "DINT",
                           frozenset([E.base_name(stack), E.base_name(sp)]))
        # The popped value must be captured now: the stack pointer moves again later.
        return self._temp_copy(value)

    def op_PUSH(self, op: Op) -> None:
        o = op.operand
        if o.is_bit:
            self.s.stack.append(("bit", self.bit(o)))
        else:
            self.s.stack.append(("val", E.to_dint(self.value(o))))

    def op_POP(self, op: Op) -> None:
        o = op.operand
        value = self._pop("bit" if o.is_bit else "val")
        if value.deps & self.ctx.layout.register_vars:
            # Saving in-flight values before the store may assign the register variable the value reads.
            value = self._temp_copy(value)
        if o.is_bit:
            self.bit_store(o, lambda: value, frozenset(["X"]))
        else:
            self._store_value(o, lambda: value)

    def op_PSW(self, op): self.s.stack.append(("val", E.to_dint(self.s.reg("WA"))))
    def op_PLW(self, op): self.s.set("WA", self._pop("val"))
    def op_PSL(self, op): self.s.stack.append(("bit", self.s.reg("LA")))
    def op_PLL(self, op): self.s.set("LA", self._pop("bit"))
    def op_PSX(self, op): self.s.stack.append(("val", self.s.reg("X")))
    def op_PLX(self, op): self.s.set("X", self._pop("val"))

    # ---- static depth (see the module docstring)

    def sync_stack(self, index: int) -> None:
        """Before op `index`: after a path that ended (RETURN, EXIT) the entries are those of the other paths, which
        left every entry in the variable of its depth."""
        stack_at = self.stack_at
        if stack_at is None:
            return
        expected = stack_at.get(index)
        if expected is None:
            return
        stack = self.s.stack
        if len(stack) != len(expected) or stack and any(kind != want for (kind, _), want in zip(stack, expected)):
            self.s.stack = [(k, E.var(self.static.slot(d, k), SLOT_TYPES[k])) for d, k in enumerate(expected)]

    def flush_stack(self) -> None:
        if self.static is None:
            super().flush_stack()   # type: ignore[misc]
            return
        for d in range(len(self.s.stack)):
            kind, value = self.s.stack[d]
            slot = self.static.slot(d, kind)
            if value.var is not None and value.var.upper() == slot.upper():
                continue
            self.prepare_write(slot.upper())    # type: ignore[attr-defined]
            value = self.s.stack[d][1]
            self.ctx.out.add(S.Assign(slot, value))
            self.s.stack[d] = (kind, E.var(slot, SLOT_TYPES[kind]))

    def call_interface(self, instance: str, interface: StackInterface, params: tuple[str, ...],
                       results: tuple[str, ...], live: frozenset[str], note: str) -> None:
        """CM of a routine with an interface: the entries it pulls become its inputs, its outputs are pushed."""
        for reg in REGS:
            if reg in live:
                self.materialize(reg)       # type: ignore[attr-defined]
            else:
                self.s.regs[reg] = None
        args = [self._pop(kind) for _, kind in reversed(interface.params)][::-1]
        # Entries below the arguments may read what the callee writes: they go to their variables first.
        self.flush_stack()
        self.prepare_write(instance.upper())     # type: ignore[attr-defined]
        self.ctx.out.add(S.Call(instance, tuple(zip(params, args)), note))
        self.forget()                       # type: ignore[attr-defined]
        for name, (_, kind) in zip(results, interface.results):
            self.s.stack.append((kind, E.var(f"{instance}.{name}", SLOT_TYPES[kind])))
