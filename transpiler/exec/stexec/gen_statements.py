"""Statements other than loops and calls: assignment, IF, CASE, EXIT, CONTINUE and RETURN."""

from __future__ import annotations

from typing import Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import Ex


class StatementCompiler(PouBase):
    """Statements other than loops and calls: assignment, IF, CASE, EXIT, CONTINUE and RETURN."""

    def stmts(self, body: list[n.Stmt]) -> None:
        start = len(self.lines)
        for s in body:
            self.stmt(s)
        if len(self.lines) == start:
            self.emit("pass")

    def stmt(self, s: n.Stmt) -> None:
        self.cur_span = s.span
        self.pre = []
        handler = getattr(self, "s_" + type(s).__name__.lower())
        handler(s)

    def cond(self, node: n.Expr, what: str) -> Ex:
        ex = self.expr(node)
        if ex.ty is not T.ERR and T.base(ex.ty) is not T.BOOL:
            return self.err(node.span, f"{what} must be BOOL, not {ex.ty}")
        return ex

    def s_assign(self, s: n.Assign) -> None:
        value = self.expr(s.value)
        target = self.lvalue(s.target)
        if value.ty is T.ERR or target.ty is T.ERR:
            return
        value = self.coerce(value, target.ty, s.value.span, "assignment")
        if value.ty is T.ERR:
            return
        self.flush_pre()
        for line in self.assign_lines(target, value):
            self.emit(line)

    def s_if(self, s: n.If) -> None:
        first = True
        opened = 0
        for cond_node, body in s.branches:
            self.cur_span = cond_node.span
            self.pre = []
            c = self.cond(cond_node, "IF condition")
            if first:
                self.flush_pre()
                self.emit(f"if {c.code}:")
                first = False
            elif self.pre:
                # A call with outputs inside an ELSIF condition must run only when the ELSIF is reached.
                self.emit("else:")
                self.indent += 1
                opened += 1
                self.flush_pre()
                self.emit(f"if {c.code}:")
            else:
                self.emit(f"elif {c.code}:")
            self.indent += 1
            self.stmts(body)
            self.indent -= 1
        if s.orelse is not None:
            self.emit("else:", s.span)
            self.indent += 1
            self.stmts(s.orelse)
            self.indent -= 1
        self.indent -= opened

    def s_case(self, s: n.Case) -> None:
        sel = self.expr(s.selector)
        if sel.ty is T.ERR:
            return
        sty = T.base(sel.ty)
        is_enum = isinstance(sty, T.EnumT)
        if not (is_enum or T.is_int(sty) or (isinstance(sty, T.LitType) and sty.cat == "int")):
            self.err(s.selector.span, f"'CASE' selector must be an integer or an enumerated value, not {sel.ty} "
                                      "(convert a BYTE/WORD first, e.g. BYTE_TO_INT)")
            return
        sel = self.val(sel)
        var = self.temp("_c")
        self.flush_pre()
        self.emit(f"{var} = {sel.code}")
        kw = "if"
        for labels, body in s.elems:
            conds = []
            singles = []
            for lab in labels:
                rng = self.case_label(lab, sel.ty, is_enum)
                if rng is None:
                    continue
                # Overlapping labels are legal for matiec (a warning only); like its if/else-if chain, the first
                # matching branch wins.
                lo, hi = rng
                if lo == hi:
                    singles.append(lo)
                else:
                    conds.append(f"{lo} <= {var} <= {hi}")
            if len(singles) == 1:
                conds.insert(0, f"{var} == {singles[0]}")
            elif singles:
                conds.insert(0, f"{var} in {tuple(singles)!r}")
            self.emit(f"{kw} {' or '.join(conds) or 'False'}:", labels[0].span if labels else s.span)
            kw = "elif"
            self.indent += 1
            self.stmts(body)
            self.indent -= 1
        if s.orelse is not None:
            self.emit("else:" if kw == "elif" else "if True:", s.span)
            self.indent += 1
            self.stmts(s.orelse)
            self.indent -= 1

    def case_label(self, lab: n.CaseLabel, sty: T.Type, is_enum: bool) -> Optional[tuple[int, int]]:
        b = T.base(sty)
        if lab.enum is not None:
            text = lab.enum
            if "#" in text:
                prefix, value = text.split("#", 1)
                if not is_enum or prefix.lower() != b.name.lower():
                    self.err(lab.span, f"CASE label '{text}': labels must be plain decimal integers or values of "
                                       "the selector's enum (matiec rejects typed and based labels)")
                    return None
            else:
                value = text
            if not is_enum:
                self.err(lab.span, f"CASE label '{text}' is not an integer (selector is {sty})")
                return None
            idx = b.index(value)
            if idx is None:
                self.err(lab.span, f"'{value}' is not a value of enum {b.name}")
                return None
            return idx, idx
        if is_enum:
            self.err(lab.span, f"integer CASE label for an enum selector ({b.name})")
            return None
        lo, hi = lab.lo, lab.hi
        if lo > hi:
            self.err(lab.span, f"empty CASE range {lo}..{hi}")
            return None
        if isinstance(b, T.Elem) and not (b.lo <= lo and hi <= b.hi):
            self.err(lab.span, f"CASE label {lo if lo == hi else f'{lo}..{hi}'} does not fit the selector type {b}")
            return None
        return lo, hi

    def s_exit(self, s: n.Exit) -> None:
        if not self.loops:
            self.err(s.span, "EXIT outside a loop")
            return
        self.emit("break")

    def s_continue(self, s: n.Continue) -> None:
        if not self.loops:
            self.err(s.span, "CONTINUE outside a loop")
            return
        for line in self.loops[-1].step_code:
            self.emit(line)
        self.emit("continue")

    def s_return(self, s: n.Return) -> None:
        self.emit(self.return_line())

    def return_line(self) -> str:
        if not self.is_function:
            return "return"
        pou = self.pou
        outs = pou.tuple_outputs
        if not outs:
            return f"return v_{pou.key}"
        return "return (" + ", ".join([f"v_{pou.key}"] + [f"v_{o.key}" for o in outs]) + ")"
