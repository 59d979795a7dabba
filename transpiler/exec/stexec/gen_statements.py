"""Statements other than loops and calls: assignment, IF, CASE, EXIT, CONTINUE and RETURN."""

from __future__ import annotations

from typing import Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.gen_schema import SwitchCompiler
from transpiler.exec.stexec.pycode import Ex


# A CASE with more arms than this, all disjoint intervals, becomes a binary search (case_tree); leaves of at most
# _CASE_LEAF intervals are tested in a row.
_CASE_TREE_MIN = 8
_CASE_LEAF = 4


class StatementCompiler(SwitchCompiler):
    """Statements other than loops and calls: assignment, IF, CASE, EXIT, CONTINUE and RETURN."""

    def stmts(self, body: list[n.Stmt]) -> None:
        start = len(self.lines)
        for s in body:
            self.stmt(s)
        if len(self.lines) == start:
            self.emit("pass")

    def stmt(self, s: n.Stmt) -> None:
        variants = self.variants_of(s)
        if variants:
            self.switched_stmt(s, variants)
        else:
            self.plain_stmt(s)

    def plain_stmt(self, s: n.Stmt) -> None:
        self.cur_span = s.span
        self.pre = []
        handler = getattr(self, "s_" + type(s).__name__.lower())
        handler(s)

    def cond(self, node: n.Expr, what: str) -> Ex:
        variants = self.variants_of(node)
        if variants:
            return self.switched_expr(node, lambda x: self.plain_cond(x, what), variants)
        return self.plain_cond(node, what)

    def plain_cond(self, node: n.Expr, what: str) -> Ex:
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
        selector_variants = self.variants_of(s.selector)
        sel = (self.switched_expr(s.selector, self.expr, selector_variants) if selector_variants
               else self.expr(s.selector))
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
        swaps = self.variants_of(s)
        if swaps:
            self.case_swaps(s, var, swaps)
        arms = self.case_intervals(s, sel.ty, is_enum)
        if arms is not None and len(arms) > _CASE_TREE_MIN:
            self.case_tree(s, var, arms, sel.ty)
            return
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

    def case_intervals(self, s: n.Case, sty: T.Type, is_enum: bool) -> Optional[list[tuple[int, int, int]]]:
        """(lo, hi, arm) sorted by lo when every arm's labels form one interval and no two arms overlap, else None
        (the if/elif chain keeps the first-match rule of overlapping labels). Labels are only checked here; the
        errors of bad labels are reported once, by the chain or the tree that follows."""
        out = []
        for arm, (labels, _body) in enumerate(s.elems):
            ranges = []
            for lab in labels:
                if lab.enum is not None:
                    return None
                if is_enum or lab.lo > lab.hi:
                    return None
                ranges.append((lab.lo, lab.hi))
            if not ranges:
                return None
            ranges.sort()
            lo, hi = ranges[0]
            for a, b in ranges[1:]:
                if a > hi + 1:
                    return None              # two intervals: the arm's body would be emitted twice
                hi = max(hi, b)
            out.append((lo, hi, arm))
        out.sort()
        if any(b[0] <= a[1] for a, b in zip(out, out[1:])):
            return None
        return out

    def case_tree(self, s: n.Case, var: str, arms: list[tuple[int, int, int]], sty: T.Type) -> None:
        """A CASE of many disjoint intervals as a binary search over them: log2(arms) comparisons instead of one per
        arm before the match (an indexed-access helper has hundreds of arms and runs hundreds of times a cycle).
        The ELSE part runs once after the tree, when a flag says no interval matched."""
        for labels, _body in s.elems:
            for lab in labels:
                if self.case_label(lab, sty, False) is None:       # the range checks of the chain
                    return
        flag = self.temp("_m") if s.orelse is not None else None
        if flag is not None:
            self.emit(f"{flag} = True")
        self._case_node(s, var, arms, flag)
        if flag is not None:
            self.emit(f"if not {flag}:", s.span)
            self.indent += 1
            self.stmts(s.orelse)
            self.indent -= 1

    def _case_node(self, s: n.Case, var: str, arms: list[tuple[int, int, int]], flag: Optional[str]) -> None:
        if len(arms) <= _CASE_LEAF:
            kw = "if"
            for lo, hi, arm in arms:
                labels, body = s.elems[arm]
                test = f"{var} == {lo}" if lo == hi else f"{lo} <= {var} <= {hi}"
                self.emit(f"{kw} {test}:", labels[0].span if labels else s.span)
                kw = "elif"
                self.indent += 1
                self.stmts(body)
                self.indent -= 1
            if flag is not None:
                self.emit("else:")
                self.indent += 1
                self.emit(f"{flag} = False")
                self.indent -= 1
            return
        mid = len(arms) // 2
        self.emit(f"if {var} < {arms[mid][0]}:")
        self.indent += 1
        self._case_node(s, var, arms[:mid], flag)
        self.indent -= 1
        self.emit("else:")
        self.indent += 1
        self._case_node(s, var, arms[mid:], flag)
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
