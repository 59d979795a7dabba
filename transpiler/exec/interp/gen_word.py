"""Word instructions in the generated code: word logic, arithmetic with its flags, compares, shifts, bit operations,
the extended instructions (A-23) and brackets."""

from __future__ import annotations

from transpiler.exec.interp.gen_exprs import LOGIC_OPS, REL, bit_mask, gate, norm, sext_expr, signed_literal
from transpiler.ir import Op, Operand


class WordCode:
    """Mixin of the code generator for the word accumulator; uses `out`, `sem`, `itf`, `brackets`, `program`,
    `op_index` and the operand access of AccessCode."""

    # word logic, arithmetic, comparisons

    def _word_gate(self, c: str, o: Operand, opid: int, ind: int) -> None:
        n = self.width(o)
        m = -1 if n == 32 else (1 << n) - 1
        u = self.value(o, "mask" if n < 32 else "sign")
        if c == "WAND":
            expr = f"WA & ({u} | {~m})" if n < 32 else f"WA & {u}"
        elif c == "WANDN":
            expr = f"WA & ~{u}"
        elif c == "WOR":
            expr = f"WA | {u}"
        elif c == "WORN":
            expr = f"WA | ({u} ^ {m})"
        elif c == "WXOR":
            expr = f"WA ^ {u}"
        else:
            expr = f"WA ^ ({u} ^ {m})"
        self.out(ind, f"WA = {expr}", opid)

    def _arith(self, c: str, left: str, right: str, opid: int, ind: int) -> None:
        """WA := left OP right with the flags of 6.5 (left is WA, or the saved value of a bracket)."""
        if c in ("ADD", "SUB"):
            sym = "+" if c == "ADD" else "-"
            if self.sem["add_overflow"] == "flag":
                # A-09 alternative: an overflow sets the multiplication error marker
                self.out(ind, f"_r = {left} {sym} {right}", opid)
                self.out(ind, f"WA = {norm('_r')}", opid)
                self.out(ind, f"if WA != _r: M[{self.itf.mul_err}] = 1", opid)
            else:
                self.out(ind, f"WA = {norm(f'{left} {sym} {right}')}", opid)
        elif c == "MUL":
            self.out(ind, f"_p = {left} * {right}", opid)
            self.out(ind, f"_r = {norm('_p')}", opid)
            self.out(ind, f"M[{self.itf.mul_err}] = _r != _p", opid)
            if self.sem["mul_overflow_result"] == "unchanged":
                self.out(ind, f"WA = _r if _r == _p else {left}", opid)
            else:
                self.out(ind, "WA = _r", opid)
        else:
            flag = self.itf.div_err if c == "DIV" else self.itf.mod_err
            if (opid, 0) in self.value_slot:
                # value profile: a zero and a non-zero divisor (slots 0 and 1); the divisor is read once
                self.out(ind, f"_cr = {right}; _vp[{self.value_slot[opid, 0]} + (_cr != 0)] = 1", opid)
                right = "_cr"
            self.out(ind, f"WA, M[{flag}] = _{c.lower()}({left}, {right})", opid)

    def _op_CMP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        n = self.width(o)
        rel = REL[op.rel]
        if self.sem["compare_signedness"] == "unsigned":
            m = (1 << n) - 1
            left, right = f"(WA & {m})", self.value(o, "mask") if n < 32 else f"({self.value(o)} & {m})"
        else:
            left, right = sext_expr('WA', n), self.value(o)
        if (opid, 0) in self.bound_slot:
            # boundaries (coverage): mark left - right when it is -1, 0 or 1 (slots opid/-1, 0, 1 are consecutive);
            # each operand is read once, as without the marks (an indexed read may fault)
            self.out(ind, f"_cl = {left}; _cr = {right}", opid)
            self.out(ind, f"if -1 <= _cl - _cr <= 1: _bd[_cl - _cr + {self.bound_slot[opid, 0]}] = 1", opid)
            left, right = "_cl", "_cr"
        self.set_la(ind, f"{left} {rel} {right}", opid)

    def _op_SHL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if self.sem["shift_semantics"] == "fault":
            self.out(ind, f"WA = _shl(WA, {self.value(op.operand)})", opid)
        elif op.operand.kind == "K":
            self.out(ind, f"WA = {norm(f'WA << {op.operand.addr & 31}')}", opid)
        else:
            self.out(ind, f"WA = {norm(f'WA << ({self.value(op.operand)} & 31)')}", opid)

    def _op_SHR(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if self.sem["shift_semantics"] == "fault":
            self.out(ind, f"WA = _shr(WA, {self.value(op.operand)})", opid)
        elif op.operand.kind == "K":
            self.out(ind, f"WA >>= {op.operand.addr & 31}", opid)
        else:
            self.out(ind, f"WA >>= ({self.value(op.operand)} & 31)", opid)

    def _bitmask(self, o: Operand) -> str:
        if o.kind == "K":
            return signed_literal(bit_mask(o.addr & 31))
        return f"(-2147483648 if ({self.value(o)} & 31) == 31 else 1 << ({self.value(o)} & 31))"

    def _op_BS(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA |= {self._bitmask(op.operand)}", opid)

    def _op_BC(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA &= ~{self._bitmask(op.operand)}", opid)

    def _op_BT(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        k = str(o.addr & 31) if o.kind == "K" else f"({self.value(o)} & 31)"
        self.set_la(ind, f"(WA >> {k}) & 1", opid)

    # extended instructions

    def _op_INC(self, op: Op, opid: int, ind: int, *_: object, step: int = 1) -> None:
        o = op.operand
        if o.is_bit:
            # a bit operand counts modulo 2 (own reading of "op := op + 1 (wrap)")
            self.bit_store(ind, o, f"{self.bit(o)} ^ 1", opid)
        else:
            self.store(ind, o, f"{self.value(o)} {'+' if step > 0 else '-'} 1", opid)

    def _op_DEC(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self._op_INC(op, opid, ind, step=-1)

    def _op_INCW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {norm('WA + 1')}", opid)

    def _op_DECW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {norm('WA - 1')}", opid)

    def _op_INCX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        # X always holds a value of its width (x_store), so only its largest value wraps
        top = 32767 if self.x16 else 2147483647
        self.out(ind, f"X = X + 1 if X < {top} else {-top - 1}", opid)

    def _op_DECX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        top = 32767 if self.x16 else 2147483647
        self.out(ind, f"X = X - 1 if X > {-top - 1} else {top}", opid)

    def _op_NOTL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, f"{self.la()} ^ 1", opid)

    def _op_NOTW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, "WA = ~WA", opid)

    def _op_TWOC(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {norm('-WA')}", opid)

    # brackets (6.9, 17b.4, A-04, A-18)

    def _op_BOPEN(self, op: Op, opid: int, ind: int, f: int, *_: object) -> None:
        saved = f"_b{len(self.brackets)}"
        width = 32
        if self.sem["bracket_width"] == "operand":
            width = self._first_inner_load_width(f, opid)
        self.brackets.append((op, saved, width))
        self.out(ind, f"{saved} = {self.la() if op.bracket.mode == 'LOGIC' else 'WA'}", opid)

    def _first_inner_load_width(self, f: int, opid: int) -> int:
        """A-18 alternative: the width of the first word load inside the bracket."""
        ops = self.program.files[f].ops
        depth = 0
        for op in ops[self.op_index[opid][1] + 1:]:
            if op.code == "BOPEN":
                depth += 1
            elif op.code == "BCLOSE":
                if depth == 0:
                    break
                depth -= 1
            elif op.code in ("WLD", "WLDN", "WNEG") and op.operand is not None:
                return self.width(op.operand)
            elif op.code == "LDBITS":
                return op.nbits
        return 32

    def _op_BCLOSE(self, op: Op, opid: int, ind: int, *_: object) -> None:
        opened, s, width = self.brackets.pop()
        br = opened.bracket
        kind = br.op
        if kind in LOGIC_OPS and br.mode == "LOGIC":
            inner = self.la()
            if br.load:
                self.set_la(ind, inner if kind in ("A", "O", "XO") else f"({inner} ^ 1)", opid)
            else:
                self.set_la(ind, gate(kind, s, inner, "(({}) ^ 1)"), opid)
        elif kind in LOGIC_OPS:
            combined = gate(kind, s, "WA", "~{}")
            if width < 32:
                m = (1 << width) - 1
                combined = f"({s} & {~m}) | (({combined}) & {m})"
            self.out(ind, f"WA = {combined}", opid)
        elif kind in ("+", "-", "x", "/", "MOD"):
            code = {"+": "ADD", "-": "SUB", "x": "MUL", "/": "DIV", "MOD": "MOD"}[kind]
            self._arith(code, s, "WA", opid, ind)
        else:
            rel = REL[kind]
            if self.sem["compare_signedness"] == "unsigned":
                m = (1 << width) - 1
                self.set_la(ind, f"({s} & {m}) {rel} (WA & {m})", opid)
            else:
                self.set_la(ind, f"{sext_expr(s, width)} {rel} {sext_expr('WA', width)}", opid)
