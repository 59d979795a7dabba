"""In-flight values: when symbolic registers, stack entries and bracket frames must be written to variables."""

from __future__ import annotations

from typing import Callable

from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.exprs import Expr
from transpiler.backends.st.liveness import REGS
from transpiler.backends.st.routine import ExecutorPart


class InFlightMixin(ExecutorPart):
    """Saves values that read a variable before it is written; flushes registers and the data stack at boundaries."""

    def _dependents(self, base: str) -> list[tuple[str, str | int]]:
        """The in-flight values that read `base`: registers, stack entries, bracket frames."""
        found: list[tuple[str, str | int]] = [
            ("reg", name) for name, value in self.s.regs.items() if value is not None and base in value.deps]
        if self.s.stack:
            found += [("stack", k) for k, (_, value) in enumerate(self.s.stack) if base in value.deps]
        if self.s.frames:
            found += [("frame", k) for k, frame in enumerate(self.s.frames) if base in frame.saved.deps]
        return found

    def prepare_write(self, base: str, keep: frozenset[str] = frozenset()) -> list[str]:
        """Before `base` is assigned: save every in-flight value that reads it.

        Registers still live after this op go to their variables; registers in `keep` (read by the
        pending statement itself) stay symbolic and are returned, to be dropped once it is emitted.
        """
        dependents = self._dependents(base)
        if not dependents:
            return []
        live = self.ctx.live_after(self.index)
        deferred: list[str] = []
        for kind, key in dependents:
            if kind == "reg":
                if key in live or self.s.frames or self.s.stack:
                    self.materialize(key)
                elif key in keep:
                    deferred.append(key)
                else:
                    self.s.regs[key] = None
            elif kind == "stack":
                entry_kind, value = self.s.stack[key]
                name = self.ctx.temp(value.typ)
                self._assign_raw(name, value)
                self.s.stack[key] = (entry_kind, E.var(name, value.typ))
            else:
                frame = self.s.frames[key]
                name = self.ctx.temp(frame.saved.typ)
                self._assign_raw(name, frame.saved)
                frame.saved = E.var(name, frame.saved.typ)
        return deferred

    def saves_nothing(self, base: str, live: frozenset[str]) -> bool:
        """Assigning `base` needs no value in flight saved: each value that reads it is a register not in `live`
        (prepare_write drops or defers such a register; nothing is saved while the stack or a bracket is open)."""
        dependents = self._dependents(base)
        return not dependents or not self.s.frames and not self.s.stack and all(
            kind == "reg" and key not in live for kind, key in dependents)

    def drop(self, regs: list[str]) -> None:
        for r in regs:
            self.s.regs[r] = None

    def materialize(self, reg: str) -> None:
        value = self.s.regs[reg]
        if value is None:
            return
        name = self.ctx.register(reg)
        if value.var is not None and value.var.upper() == name.upper():
            self.s.regs[reg] = None
            return
        # Other in-flight values reading this register variable are saved first; the value itself
        # is evaluated before the assignment, so it may read the variable.
        self.s.regs[reg] = None
        self.prepare_write(E.base_name(name))
        self.ctx.out.add(S.Assign(name, value))

    def _assign_raw(self, lvalue: str, value: Expr) -> None:
        self.ctx.out.add(S.Assign(lvalue, value))

    def store(self, target: Callable[[], Expr], value: Callable[[], Expr], keep: frozenset[str]) -> Expr:
        """Emit `target := value`; both are built after in-flight values that read the target were saved."""
        t = target()
        written = E.written_name(t)
        if not self._dependents(written):
            # (most stores: no value in flight reads the target, nothing is saved, the target stays as built)
            self.ctx.out.add(S.Assign(t.text, value()))
            return t
        deferred = self.prepare_write(written, keep)
        t = target()
        v = value()
        self.ctx.out.add(S.Assign(t.text, v))
        self.drop(deferred)
        return t

    def flush(self, live: frozenset[str]) -> None:
        """At a block boundary: live registers into their variables, the data stack into the real stack."""
        self.flush_stack()
        for reg in REGS:
            if reg in live:
                self.materialize(reg)
            else:
                self.s.regs[reg] = None

    def forget(self) -> None:
        """After a call, a return or a join of paths: every register is read from its variable again."""
        self.s.regs = dict.fromkeys(REGS)

    def la_is(self, value: bool) -> Expr:
        """The condition `LA = value`: LA, or NOT LA."""
        la = self.s.reg("LA")
        return la if value else E.b_not(la)

    def snapshot(self) -> tuple[dict, list]:
        return dict(self.s.regs), list(self.s.stack)

    def restore(self, snap: tuple[dict, list]) -> None:
        self.s.regs, self.s.stack = dict(snap[0]), list(snap[1])

    def keep_live(self, live: frozenset[str]) -> None:
        """Before a branch: live registers into their variables, the rest stays symbolic for the branch."""
        self.flush_stack()
        for reg in REGS:
            if reg in live:
                self.materialize(reg)

    def flush_stack(self) -> None:
        entries, self.s.stack = self.s.stack, []
        for kind, value in entries:
            self._real_push(kind, value)

    def _stable(self, e: Expr) -> Expr:
        """An expression that may be evaluated twice: simple ones as they are, others through a temporary."""
        return e if e.simple else self._temp_copy(e)

    def _temp_copy(self, e: Expr) -> Expr:
        """`e` assigned to a new temporary, which then stands for it (with the same value range)."""
        name = self.ctx.temp(e.typ)
        self._assign_raw(name, e)
        return E.Expr(name, e.typ, frozenset([name.upper()]), e.lo, e.hi, var=name)
