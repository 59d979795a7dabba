"""Loops: WHILE, REPEAT and FOR, each under the watchdog of loop_limit iterations."""

from __future__ import annotations

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import P_ADD, P_CMP, P_NOT, Ex, Loop, const_ex, paren, py_literal


class LoopCompiler(PouBase):
    """Loops: WHILE, REPEAT and FOR, each under the watchdog of loop_limit iterations."""

    def loop_guard_open(self) -> None:
        self.emit("for _ in _LOOP_RANGE:")

    def loop_guard_close(self, span: Span) -> None:
        self.emit("else:", span)
        self.indent += 1
        self.emit(f"_loop_trap({self.ctx.loop_limit})", span)
        self.indent -= 1

    def s_while(self, s: n.While) -> None:
        c = self.cond(s.cond, "WHILE condition")
        pre, self.pre = self.pre, []
        self.loop_guard_open()
        self.indent += 1
        for line in pre:
            self.emit(line)
        self.emit(f"if not {paren(c, P_NOT)}:")
        self.indent += 1
        self.emit("break")
        self.indent -= 1
        self.loops.append(Loop("while", []))
        self.stmts(s.body)
        self.loops.pop()
        self.indent -= 1
        self.loop_guard_close(s.span)

    def s_repeat(self, s: n.Repeat) -> None:
        saved = self.cur_span
        self.cur_span = s.cond.span
        c = self.cond(s.cond, "UNTIL condition")
        test = self.pre + [f"if {c.code}: break"]
        self.pre = []
        self.cur_span = saved
        self.loop_guard_open()
        self.indent += 1
        self.loops.append(Loop("repeat", test))
        self.stmts(s.body)
        self.loops.pop()
        self.cur_span = s.cond.span
        for line in test:
            self.emit(line)
        self.indent -= 1
        self.loop_guard_close(s.span)

    def s_for(self, s: n.For) -> None:
        v = self.lookup(s.var)
        if v is None:
            self.err(s.var_span, f"undeclared FOR control variable '{s.var}'")
            return
        ctl = self.var_ex(v)
        if not T.is_int(ctl.ty):
            self.err(s.var_span, f"invalid data type {ctl.ty} for the FOR control variable (needs an integer type)")
            return
        if not ctl.writable:
            self.err(s.var_span, f"FOR control variable: {ctl.why_readonly}")
            return
        start = self.coerce(self.expr(s.start), ctl.ty, s.start.span, "FOR start value")
        end = self.coerce(self.expr(s.end), ctl.ty, s.end.span, "FOR end value")
        step = self.coerce(self.expr(s.step), ctl.ty, s.step.span, "FOR step") if s.step is not None \
            else const_ex(1, ctl.ty)
        if T.ERR in (start.ty, end.ty, step.ty):
            return
        self.flush_pre()
        self.emit(f"{ctl.code} = {start.code}")
        if step.const is None:
            step_var = self.temp("_s")
            self.emit(f"{step_var} = {step.code}")
            step_code = step_var
            test = f"({ctl.code} <= {paren(end, P_CMP + 1)} if {step_var} > 0 else {ctl.code} >= {paren(end, P_CMP + 1)})"
        else:
            step_code = py_literal(step.const)[0]
            test = f"{ctl.code} {'<=' if step.const > 0 else '>='} {paren(end, P_CMP + 1)}"
        incr = self.wrap(Ex(f"{ctl.code} + {step_code}", ctl.ty, P_ADD, False)).code
        self.loop_guard_open()
        self.indent += 1
        self.emit(f"if not ({test}):")
        self.indent += 1
        self.emit("break")
        self.indent -= 1
        self.loops.append(Loop("for", [f"{ctl.code} = {incr}"]))
        self.stmts(s.body)
        self.loops.pop()
        self.emit(f"{ctl.code} = {incr}")
        self.indent -= 1
        self.loop_guard_close(s.span)
