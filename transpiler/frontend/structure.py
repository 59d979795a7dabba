"""Structure matching: IFT/IFF ... ELSE ... ENDI, WHILET/WHILEF ... ENDW and REPEAT ... UNTILT/UNTILF become jumps."""

from __future__ import annotations

from transpiler.diagnostics import Diagnostics
from transpiler.frontend.opcodes import CONTROL, MAX_NESTING, STRUCT_OPEN
from transpiler.ir import Op, new_op
from transpiler.language.semantics import Semantics
from transpiler.records import replaced


class StructureMatcher:
    """Matches the structured keywords of one file and patches the jump targets into its ops (a shared list)."""

    def __init__(self, ops: list[Op], semantics: Semantics, diags: Diagnostics):
        self.ops = ops
        self.semantics = semantics
        self.diags = diags
        self.structs: list[list] = []     # [keyword, op index, else index]

    def lower(self, m: str, base: dict, index: int) -> Op:
        span = base["span"]
        structs = self.structs
        if m in STRUCT_OPEN:
            if len(structs) == MAX_NESTING:      # once per too-deep nest, not for every deeper level
                self.diags.report("E-STRUCT-NEST", span, f"structured statements nested deeper than {MAX_NESTING}")
            structs.append([m, index, None])
            code = {"IFT": "JPF", "IFF": "JPT", "WHILET": "JPF", "WHILEF": "JPT", "REPEAT": "NOP"}[m]
            return new_op(code, **base)
        expected = {"ELSE": ("IFT", "IFF"), "ENDI": ("IFT", "IFF"), "ENDW": ("WHILET", "WHILEF"),
                    "UNTILT": ("REPEAT",), "UNTILF": ("REPEAT",)}[m]
        if not structs or structs[-1][0] not in expected or (m == "ELSE" and structs[-1][2] is not None):
            return self._mismatch(m, base, expected)
        return self._close(m, base, index)

    def _mismatch(self, m: str, base: dict, expected: tuple[str, ...]) -> Op:
        structs = self.structs
        opener = structs[-1][0] if structs else "nothing"
        self.diags.report("E-STRUCT-NEST", base["span"], f"{m} does not match the open structure ({opener})")
        # Interleaved structures (IFT WHILET ENDI ENDW): forget the opener this keyword was meant for, so
        # that the inner one still closes normally and the overlap is one error, not three.
        if m != "ELSE":
            for k in range(len(structs) - 1, -1, -1):
                if structs[k][0] in expected:
                    del structs[k]
                    break
        return new_op("NOP", **base)

    def _close(self, m: str, base: dict, index: int) -> Op:
        """ELSE, ENDI, ENDW, UNTILT or UNTILF that matches the innermost open structure."""
        frame = self.structs[-1]
        if m == "ELSE":
            frame[2] = index
            self._patch(frame[1], index + 1)
            return new_op("JP", **base)          # target patched at ENDI
        self.structs.pop()
        opener_index = frame[1]
        if m == "ENDI":
            if frame[2] is not None:
                self._patch(frame[2], index)
            else:
                self._patch(opener_index, index)
            return new_op("NOP", **base)
        if m == "ENDW":
            self._patch(opener_index, index + 1)
            back = opener_index
            if self.semantics["while_retest"] == "chain":
                back = self._chain_start(opener_index)
            return new_op("JP", target=back, **base)
        return new_op("JPF" if m == "UNTILT" else "JPT", target=opener_index, **base)

    def report_unclosed(self) -> None:
        for frame in self.structs:
            self.diags.report("E-STRUCT-NEST", self.ops[frame[1]].span, f"{frame[0]} is never closed")

    def _chain_start(self, index: int) -> int:
        """The first instruction of the logic chain before ops[index] (while_retest = chain)."""
        start = index
        for j in range(index - 1, -1, -1):
            o = self.ops[j]
            if o.code in ("LBL", "KFIELD") or o.mnemonic in CONTROL or o.code in (
                    "ST", "STN", "SET", "RES", "SETN", "RESN", "WST", "SST", "STBITS"):
                break
            start = j
        return start

    def _patch(self, index: int, target: int) -> None:
        self.ops[index] = replaced(self.ops[index], target=target)
