"""Data stack and string instructions in the generated code (6.10, 6.16)."""

from __future__ import annotations

from transpiler.exec.interp.gen_exprs import REL
from transpiler.ir import Op


class StackStringCode:
    """Mixin of the code generator: PUSH POP PSW PLW PSL PLL PSX PLX and SLD SCAT SST SCMP; uses `out`, `sem`
    and the operand access of AccessCode."""

    # data stack (6.10, A-19, A-20)

    def _op_PUSH(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.is_bit:
            self.out(ind, f"_ps16({self.bit(o)} << 7)", opid)
        else:
            self.out(ind, f"_ps32({self.value(o)})", opid)

    def _op_POP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        o = op.operand
        if o.is_bit:
            self.bit_store(ind, o, "(_pl16() >> 7) & 1", opid)
        else:
            self.store(ind, o, "_pl32()", opid)

    def _op_PSW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, "_ps32(WA)", opid)

    def _op_PLW(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, "WA = _pl32()", opid)

    def _op_PSL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"_ps16({self.la()} << 7)", opid)

    def _op_PLL(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, "(_pl16() >> 7) & 1", opid)

    def _op_PSX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if int(self.sem["psx_width"]) == 16:
            self.out(ind, "_ps16(X & 65535)", opid)
        else:
            self.out(ind, "_ps32(X)", opid)

    def _op_PLX(self, op: Op, opid: int, ind: int, *_: object) -> None:
        if int(self.sem["psx_width"]) == 16:
            self.out(ind, self.x_store("_pl16()"), opid)
        else:
            self.out(ind, self.x_store("_pl32()"), opid)

    # strings (6.16, A-50)

    def _op_SLD(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"SA = {self.string(op.operand)}", opid)

    def _op_SCAT(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"SA = _scat(SA + {self.string(op.operand)}, {opid})", opid)

    def _op_SST(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.out(ind, f"{self.string(op.operand, write=True)} = SA", opid)

    def _op_SCMP(self, op: Op, opid: int, ind: int, *_: object) -> None:
        self.set_la(ind, f"SA {REL[op.rel]} {self.string(op.operand)}", opid)
