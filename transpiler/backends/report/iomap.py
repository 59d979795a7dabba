"""The operand <-> IEC variable map (io_map.csv): how the co-simulation reads and writes each HEIDENHAIN operand in the ST program."""

from __future__ import annotations

import csv
import dataclasses
import io
import re
from typing import Callable, Iterable, Protocol

from transpiler.records import quick_init

BYTES = {"SINT": 1, "INT": 2, "DINT": 4}


class StRuntime(Protocol):
    def get(self, path: str): ...
    def set(self, path: str, value) -> None: ...


@quick_init
@dataclasses.dataclass(frozen=True)
class MapRow:
    symbol: str
    operand: str
    iec: str
    iec_type: str
    direction: str
    comment: str = ""
    address: str = ""          # the IEC located address (%IX0.3, %QX1.0) of a process-image operand


def iec_address(operand: str) -> str:
    """The located address the ST declares an input or output at: bit n of the process image is byte n div 8,
    bit n mod 8 (%IX for I, %QX for O); '' for every other operand. CODESYS, TwinCAT and OpenPLC use this form."""
    m = re.fullmatch(r"([IO])(\d+)", operand)
    if m is None:
        return ""
    addr = int(m.group(2))
    return f"%{'IX' if m.group(1) == 'I' else 'QX'}{addr // 8}.{addr % 8}"


@dataclasses.dataclass(frozen=True)
class Place:
    """Where an operand's value lives in the ST program, for executors that read many operands in one call."""

    path: str                  # the variable, or for width > 0 the array element holding the operand's first byte
    width: int = 0             # 0: the variable itself; 1, 2, 4: that many bytes of a byte array, combined
    big_endian: bool = False
    text: bool = False


@dataclasses.dataclass(frozen=True)
class Accessor:
    """Reads and writes one operand in an ST runtime with the operand's HEIDENHAIN value convention."""

    operand: str
    read: Callable[[StRuntime], int | str]
    write: Callable[[StRuntime, int | str], None]
    place: Place


def _sext(value: int, bits: int) -> int:
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >= 1 << (bits - 1) else value


def _accessor(row: MapRow) -> Accessor:
    typ = row.iec_type
    m = re.fullmatch(r"(SINT|INT|DINT)@(LE|BE)", typ)
    if m:
        # The operand lives in the byte array: combine its bytes in the profile's byte order.
        size = BYTES[m.group(1)]
        little = m.group(2) == "LE"
        am = re.fullmatch(r"(\w+)\[(\d+)\]", row.iec)
        if am is None:
            raise ValueError(f"io_map: cannot read array element '{row.iec}' of {row.operand}")
        arr, base = am.group(1), int(am.group(2))
        order = list(range(size)) if little else list(reversed(range(size)))   # significance -> byte offset

        def read(rt: StRuntime) -> int:
            value = 0
            for significance, offset in enumerate(order):
                value |= (int(rt.get(f"{arr}[{base + offset}]")) & 0xFF) << (8 * significance)
            return _sext(value, 8 * size)

        def write(rt: StRuntime, value) -> None:
            v = int(value)
            for significance, offset in enumerate(order):
                rt.set(f"{arr}[{base + offset}]", (v >> (8 * significance)) & 0xFF)

        return Accessor(row.operand, read, write, Place(row.iec, size, not little))
    if typ == "BOOL":
        return Accessor(row.operand, lambda rt, p=row.iec: 1 if rt.get(p) else 0,
                        lambda rt, v, p=row.iec: rt.set(p, bool(int(v))), Place(row.iec))
    if typ in BYTES or typ in ("LINT",):
        bits = 8 * BYTES.get(typ, 8)
        return Accessor(row.operand, lambda rt, p=row.iec: int(rt.get(p)),
                        lambda rt, v, p=row.iec, b=bits: rt.set(p, _sext(int(v), b)), Place(row.iec))
    if typ == "STRING":
        return Accessor(row.operand, lambda rt, p=row.iec: str(rt.get(p)), lambda rt, v, p=row.iec: rt.set(p, str(v)),
                        Place(row.iec, text=True))
    raise ValueError(f"io_map: unsupported IEC type '{typ}' for {row.operand}")


class IoMap:
    """All rows of an io_map, with accessors by operand text (I5, W262, MP4110.3)."""

    def __init__(self, rows: Iterable[MapRow]):
        self.rows = list(rows)
        self.by_operand: dict[str, MapRow] = {}
        for r in self.rows:
            self.by_operand.setdefault(r.operand, r)
        self._accessors: dict[str, Accessor] = {}

    def accessor(self, operand: str) -> Accessor | None:
        if operand not in self.by_operand:
            row = self._array_row(operand)
            if row is None:
                return None
            self.by_operand[operand] = row
        if operand not in self._accessors:
            self._accessors[operand] = _accessor(self.by_operand[operand])
        return self._accessors[operand]

    def _array_row(self, operand: str) -> MapRow | None:
        """Operands the program reaches only through an index live in the space's array (row `B*`, `M*`, ...)."""
        m = re.fullmatch(r"([MIOTCBWDS])(\d+)", operand)
        if m is None:
            return None
        kind, addr = m.group(1), int(m.group(2))
        space = "B*" if kind in "BWD" else f"{kind}*"
        row = self.by_operand.get(space)
        if row is None:
            return None
        if kind in "BWD":
            typ = {"B": "SINT", "W": "INT", "D": "DINT"}[kind]
            return MapRow("", operand, f"{row.iec}[{addr}]", f"{typ}@{row.iec_type.split('@')[1]}", row.direction)
        return MapRow("", operand, f"{row.iec}[{addr}]", "BOOL" if kind != "S" else "STRING", row.direction)

    @classmethod
    def from_csv(cls, text: str) -> "IoMap":
        reader = csv.DictReader(io.StringIO(text))
        need = {"symbol", "operand", "iec_variable", "iec_type", "direction"}
        if reader.fieldnames is None or not need <= set(reader.fieldnames):
            raise ValueError(f"io_map.csv needs the columns {', '.join(sorted(need))}")
        return cls(MapRow(r["symbol"], r["operand"], r["iec_variable"], r["iec_type"], r["direction"], r.get("comment", ""),
                          r.get("iec_address") or "")
                   for r in reader)

    def to_csv(self) -> str:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["symbol", "operand", "iec_variable", "iec_address", "iec_type", "direction", "comment"])
        for r in self.rows:
            w.writerow([r.symbol, r.operand, r.iec, r.address, r.iec_type, r.direction, r.comment])
        return buf.getvalue()
