"""Operand access in the generated code: registers, bit and word reads and writes, loads, stores and bit logic."""

from __future__ import annotations

import dataclasses
from typing import Callable

from transpiler.exec.interp.gen_exprs import M32, int32, norm, signed_literal
from transpiler.ir import Op, Operand


CHAIN_OPS = frozenset({"LD", "LDN", "AND", "ANDN", "OR", "ORN", "XOR", "XORN"})
_CHAIN_SYMBOLS = {"AND": "and", "OR": "or", "XOR": "^"}
_CHAIN_LIMIT = 32          # ops per folded LA expression: each change of operator nests a parenthesis


@dataclasses.dataclass(frozen=True)
class _LaChain:
    """The pending expression of LA: its text, its outermost operator (for parentheses), where it goes."""

    text: str
    top: str
    ind: int
    opid: int
    length: int = 1


class AccessCode:
    """Mixin of the code generator: expressions that read and write registers and operands, and the ops that only
    move values (loads, stores, bit logic). Uses the generator's `out`, `sem`, `shared`, `x16`, `native`, `scale`,
    `sizes`, `every_valid` and `kf_tables`."""

    # ------------------------------------------------------------------ registers

    def la(self) -> str:
        return "((WA >> 7) & 1)" if self.shared else "LA"

    def set_la(self, indent: int, expr: str, opid: int) -> None:
        if self.shared:
            # A-05 shared_bit7: the logic result is bit 7 of WA, the other bits stay.
            self.out(indent, f"WA = (WA & -129) | (({expr}) << 7)", opid)
        else:
            self.out(indent, f"LA = {expr}", opid)

    def x_store(self, expr: str) -> str:
        # Every write of X wraps to its width here (Machine.write too), so reads use X as it is.
        return f"X = (((({expr}) + 32768) & 65535) - 32768)" if self.x16 else f"X = {norm(expr)}"

    # ------------------------------------------------------------------ operands

    def width(self, o: Operand) -> int:
        if o.kind == "X":
            return 16 if self.x16 else 32
        return {"B": 8, "W": 16}.get(o.kind, 32)

    def _ix(self, o: Operand) -> str:
        """Effective address of an indexed operand (A-21): base + X, W/D scaled by the element size if set."""
        size = {"W": 2, "D": 4}.get(o.kind, 1)
        return f"X * {size} + {o.addr}" if self.scale and size > 1 else f"X + {o.addr}"

    def _ix_ok(self, o: Operand) -> str:
        # The inline test covers the valid case only; the helper raises the fault (or reads 0, A-22).
        in_range = f"0 <= (_a := {self._ix(o)}) < {self.sizes[o.kind]}"
        return in_range if self.every_valid[o.kind] else f"{in_range} and V{o.kind}[_a]"

    def _ix_read(self, o: Operand, at: Callable[[str], str], slow: str) -> str:
        """An indexed read, inline when its address is valid (`at` of the address), else the helper call `slow`."""
        if self.every_valid[o.kind]:
            # a bit or byte address in range is valid: a test of X alone, without a temporary
            return f"({at(f'X + {o.addr}')} if {-o.addr} <= X < {self.sizes[o.kind] - o.addr} else {slow})"
        return f"({at('_a')} if {self._ix_ok(o)} else {slow})"

    def bit(self, o: Operand) -> str:
        if o.indexed:
            return self._ix_read(o, lambda a: f"{o.kind}[{a}]", f"_rb({o.kind!r}, {o.addr}, X)")
        return f"{o.kind}[{o.addr}]"

    def bit_store(self, indent: int, o: Operand, expr: str, opid: int) -> None:
        if o.indexed:
            # The inline store records its address (Runtime.indexed_writes); the helper records its own.
            self.out(indent, f"if {self._ix_ok(o)}: {o.kind}[_a] = {expr}; _ixw(({o.kind!r}, _a))", opid)
            self.out(indent, f"else: _wb({o.kind!r}, {o.addr}, X, {expr})", opid)
        else:
            self.out(indent, f"{o.kind}[{o.addr}] = {expr}", opid)

    def value(self, o: Operand, ext: str = "sign") -> str:
        """read_val (5.5): ext 'sign' = sign-extended, 'zero' = zero-extended, 'mask' = the low n bits (u = v & m)."""
        k = o.kind
        if k == "K":
            return signed_literal(int32(o.addr))
        if k == "KF":
            return f"_kf({self._kf_name(o.kfield)}, X, {o.text!r})"
        if k == "X":
            return "(X & 65535)" if (ext in ("zero", "mask") and self.x16) else "X"
        signed = ext == "sign" or k == "D"
        if o.indexed:
            slow = f"_rx({k!r}, {o.addr}, X, {signed})"
            if k != "B" and not self.native:
                return slow
            return self._ix_read(o, lambda a: self._mem_at(k, a, signed), slow)
        return self._mem_at(k, o.addr, signed)

    def _mem_at(self, k: str, a: int | str, signed: bool) -> str:
        """Read of B/W/D at byte address `a` (a constant or the name of a variable)."""
        shift = lambda n: str(a >> n) if isinstance(a, int) else f"{a} >> {n}"  # noqa: E731
        if k == "B":
            return f"mb[{a}]" if signed else f"mem[{a}]"
        if self.native:
            if k == "W":
                return f"mw[{shift(1)}]" if signed else f"mwu[{shift(1)}]"
            return f"md[{shift(2)}]"
        if k == "W":
            return f"_uh(mem, {a})[0]" if signed else f"_uH(mem, {a})[0]"
        return f"_ui(mem, {a})[0]"

    def load_value(self, o: Operand) -> str:
        """Word loads honour A-06 load_extension for B and W."""
        return self.value(o, "zero" if self.sem["load_extension"] == "zero" else "sign")

    def store(self, indent: int, o: Operand, expr: str, opid: int, saturate: bool = False) -> None:
        """write_val (5.5): truncating to the operand width (or saturating, A-08)."""
        k = o.kind
        if k == "X":
            self.out(indent, self.x_store(expr), opid)
            return
        if saturate and k in ("B", "W"):
            expr = f"_sat({expr}, {8 if k == 'B' else 16})"
        if o.indexed:
            slow = f"_wx({k!r}, {o.addr}, X, {expr})"
            if k != "B" and not self.native:
                self.out(indent, slow, opid)
                return
            self.out(indent, f"if {self._ix_ok(o)}: {self._mem_store(k, '_a', expr)}; _ixw(({k!r}, _a))", opid)
            self.out(indent, f"else: {slow}", opid)
            return
        self.out(indent, self._mem_store(k, o.addr, expr), opid)

    def _mem_store(self, k: str, a: int | str, expr: str) -> str:
        mask = {"B": 255, "W": 65535, "D": M32}[k]
        if k == "B":
            return f"mem[{a}] = ({expr}) & 255"
        if self.native:
            index = (a >> (1 if k == "W" else 2)) if isinstance(a, int) else f"{a} >> {1 if k == 'W' else 2}"
            return f"{'mwu' if k == 'W' else 'mdu'}[{index}] = ({expr}) & {mask}"
        return f"_p{'H' if k == 'W' else 'I'}(mem, {a}, ({expr}) & {mask})"

    def string(self, o: Operand, write: bool = False) -> str:
        if o.kind == "STR":
            return repr(o.text)
        if o.indexed:
            return f"S[_six({o.addr}, X)]" if write else f"_srx({o.addr}, X)"
        return f"S[{o.addr}]"

    def _kf_name(self, values: tuple[int, ...]) -> str:
        values = tuple(int32(v) for v in values)
        name = self.kf_tables.get(values)
        if name is None:
            name = self.kf_tables[values] = f"_KF{len(self.kf_tables)}"
        return name

    # bit logic

    def _bit_logic(self, c: str, o: Operand, opid: int, ind: int) -> None:
        """LD LDN AND ANDN OR ORN XOR XORN, ST STN, SET RES SETN RESN."""
        if self.fuse_la and not o.indexed and c in CHAIN_OPS and opid not in self.cond_slot:
            self._chain(c, o, opid, ind)
        elif self.fuse_la and not o.indexed and c == "ST" and self.la_chain is not None:
            chain, self.la_chain = self.la_chain, None
            self.out(ind, f"{self.bit(o)} = LA = {chain.text}", chain.opid)
        elif c in ("LD", "LDN", "AND", "ANDN", "OR", "ORN", "XOR", "XORN"):
            b = self.bit(o)
            if opid in self.cond_slot:
                # MC/DC: the condition is the operand's value, read once into the local its decision records
                slot = self.cond_slot[opid]
                self.out(ind, f"_q{slot} = {b}", opid)
                b = f"_q{slot}"
            if c.endswith("N"):
                b = f"({b} ^ 1)"
            sym = {"LD": "", "AND": "&", "OR": "|", "XOR": "^"}[c.rstrip("N")]
            if sym and (opid, 0) in self.value_slot:
                # value profile: LA and the operand differ, LA 0 (slot 0) or 1 (slot 1), the only pairs on which
                # AND and OR disagree; the operand is read once, as without the profile (an indexed read may fault)
                la = self.la()
                self.out(ind, f"_b = {b}", opid)
                self.out(ind, f"if {la} != _b: _vp[{self.value_slot[opid, 0]} + {la}] = 1", opid)
                b = "_b"
            if not sym:
                self.set_la(ind, b, opid)
            elif self.shared:
                self.set_la(ind, f"{self.la()} {sym} {b}", opid)
            else:
                self.out(ind, f"LA {sym}= {b}", opid)
        elif c in ("ST", "STN"):
            self.bit_store(ind, o, self.la() if c == "ST" else f"({self.la()} ^ 1)", opid)
        else:
            cond = self.la() if c in ("SET", "RES") else f"not {self.la()}"
            self.out(ind, f"if {cond}:", opid)
            self.bit_store(ind + 1, o, "1" if c in ("SET", "SETN") else "0", opid)

    def _chain(self, c: str, o: Operand, opid: int, ind: int) -> None:
        """Fold a bit load or gate on a named operand into the pending expression of LA (fast variant).

        A run of these ops becomes one assignment `LA = M[1] and not M[2] or M[3]`: no store and reload of LA per
        op, and `and`/`or` skip the reads that cannot change the result. The reads may be skipped or delayed
        because nothing in the run writes or faults (named bit operands only), and every other line flushes the
        expression first (`out`). Bits are 0 or 1, so `and`/`or` give the values `&`/`|` give (as 0, 1 or a bool,
        which LA already holds after a comparison)."""
        b = self.bit(o)
        if c in ("LD", "LDN"):
            # a load makes a pending expression dead: its reads are dropped, they have no effect
            self.la_chain = _LaChain(f"not {b}" if c == "LDN" else b, "not" if c == "LDN" else "atom", ind, opid)
            return
        chain = self.la_chain or _LaChain("LA", "atom", ind, opid)
        kind = c.rstrip("N")
        sym = _CHAIN_SYMBOLS[kind]
        if c.endswith("N"):
            right = f"({b} ^ 1)" if kind == "XOR" else f"not {b}"
        else:
            right = b
        left = chain.text if chain.top in ("atom", sym) else f"({chain.text})"
        self.la_chain = _LaChain(f"{left} {sym} {right}", sym, chain.ind, chain.opid, chain.length + 1)
        if self.la_chain.length >= _CHAIN_LIMIT:
            self.flush_la()

    def flush_la(self) -> None:
        """Emit the pending LA expression, if any (before any other line, see `out`)."""
        chain, self.la_chain = self.la_chain, None
        if chain is not None:
            self.out(chain.ind, f"LA = {chain.text}", chain.opid)

    # loads and stores

    def _op_WLD(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {self.load_value(op.operand)}", opid)

    def _op_WLDN(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if self.sem["ln_word"] == "operand_width" and self.width(o) < 32:
            # A-07 alternative: the complement over the operand width only (upper bits 0).
            self.out(ind, f"WA = ~{self.value(o, 'mask')} & {(1 << self.width(o)) - 1}", opid)
        else:
            self.out(ind, f"WA = ~{self.load_value(o)}", opid)

    def _op_WNEG(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"WA = {norm('-' + self.load_value(op.operand))}", opid)

    def _op_LDBITS(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.indexed:
            self.out(ind, f"WA = _packx({o.kind!r}, {o.addr}, X, {op.nbits})", opid)
        else:
            self.out(ind, f"WA = _pack({o.kind}, {o.addr}, {op.nbits})", opid)

    def _op_STBITS(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.indexed:
            self.out(ind, f"_unpackx({o.kind!r}, {o.addr}, X, {op.nbits}, WA)", opid)
        else:
            self.out(ind, f"_unpack({o.kind}, {o.addr}, {op.nbits}, WA)", opid)

    def _op_WST(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.store(ind, op.operand, "WA", opid, saturate=self.sem["store_truncation"] == "saturate")
