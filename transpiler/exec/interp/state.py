"""Machine memory: the five bit spaces, byte memory with the profile byte order (B/W/D overlap), strings, access functions."""

from __future__ import annotations

import dataclasses
import struct
import sys

from transpiler.language.semantics import Profile, Semantics

BIT_SPACES = "MIOTC"
MEM_WIDTH = {"B": 1, "W": 2, "D": 4}
INT32_MIN = -(1 << 31)


def byte_cells(kind: str, addr: int) -> list[tuple[str, int]]:
    """A B/W/D operand as the bytes B<n> it covers (the memory overlaps byte-wise); any other operand as itself."""
    width = MEM_WIDTH.get(kind)
    return [(kind, addr)] if width is None else [("B", byte) for byte in range(addr, addr + width)]


def nonzero_positions(data: bytes | bytearray) -> list[int]:
    """Positions of the non-zero bytes of `data`, found at C speed (cheap when there are few)."""
    ones = data.translate(_NONZERO_TO_ONE)
    found = []
    i = ones.find(1)
    while i >= 0:
        found.append(i)
        i = ones.find(1, i + 1)
    return found


_NONZERO_TO_ONE = bytes([0]) + bytes([1]) * 255



def memory_size(profile: Profile) -> int:
    """Byte memory size: the profile range plus interface bytes, rounded up to whole double words."""
    itf_bytes = max(profile.interface.interface_bytes, default=0) + 1
    code_word = profile.interface.module_err_code_word
    size = max(profile.ranges.size("B"), itf_bytes, (code_word or 0) + 2)
    return (size + 3) // 4 * 4          # memoryview casts need whole elements


def space_size(profile: Profile, kind: str) -> int:
    """Array size of a bit space (M I O T C), the byte memory (B W D) or the string memory (S)."""
    if kind in MEM_WIDTH:
        return memory_size(profile)
    if kind == "S":
        return profile.ranges.size("S")
    return _space_size(profile, kind)


def _space_size(profile: Profile, kind: str) -> int:
    """Array size for a bit space: the profile range plus every interface operand of that kind (17b.1)."""
    size = profile.ranges.size(kind)
    if kind == "M":
        itf = profile.interface
        extra = [*itf.interface_markers, itf.error_markers[1], itf.mul_err, itf.div_err, itf.mod_err, itf.module_err]
        extra += [m for m in (itf.first_cycle, itf.program_restart, itf.mp_restart) if m is not None]
        size = max(size, max(extra) + 1)
    return size


def _valid_table(profile: Profile, kind: str, size: int) -> bytes:
    """1 for every address an indexed operand may reach: inside the profile range or an interface operand."""
    table = bytearray(size)
    for lo, hi in getattr(profile.ranges, kind):
        table[lo:hi + 1] = b"\x01" * (min(hi, size - 1) - lo + 1)
    for addr in range(size):
        if not table[addr] and profile.is_interface(kind, addr):
            table[addr] = 1
    return bytes(table)


def every_address_valid(profile: Profile, kind: str) -> bool:
    """Whether an indexed bit or byte operand of `kind` may reach every address of its array: then the range test is
    the whole check of an effective address (W and D also need alignment, S is never checked inline)."""
    if kind not in BIT_SPACES and kind != "B":
        return False
    return 0 not in _valid_table(profile, kind, space_size(profile, kind))


@dataclasses.dataclass
class Snapshot:
    """Copy of the memory taken before the main program (used to re-run a cycle exactly)."""

    bits: tuple[bytearray, ...]
    mem: bytearray
    strings: list[str]


class MachineState:
    """All PLC operand memory of one machine; generated code works on the arrays directly."""

    def __init__(self, profile: Profile, semantics: Semantics):
        self.profile = profile
        self.little = semantics.little_endian
        self.string_len = profile.string_len
        self.sizes = {k: _space_size(profile, k) for k in BIT_SPACES}
        self.M = bytearray(self.sizes["M"])
        self.I = bytearray(self.sizes["I"])
        self.O = bytearray(self.sizes["O"])
        self.T = bytearray(self.sizes["T"])
        self.C = bytearray(self.sizes["C"])
        self.mem_size = memory_size(profile)
        self.mem = bytearray(self.mem_size)
        self.S: list[str] = [""] * profile.ranges.size("S")
        self.process_inputs = bytearray(self.sizes["I"])  # what the process drives; latched in phase 2
        self.process_outputs = bytearray(self.sizes["O"])  # the output image handed over in phase 6
        self.valid = {k: _valid_table(profile, k, self.sizes[k]) for k in BIT_SPACES}
        self.valid["B"] = _valid_table(profile, "B", self.mem_size)
        self.valid["S"] = bytes([1]) * len(self.S)
        # W/D: 1 where a whole, aligned operand starts (indexed accesses check one table entry)
        for kind, size in (("W", 2), ("D", 4)):
            table = bytearray(self.mem_size)
            byte_ok = self.valid["B"]
            for addr in range(0, self.mem_size - size + 1, size):
                if byte_ok.count(1, addr, addr + size) == size:
                    table[addr] = 1
            self.valid[kind] = bytes(table)
        # Native memoryviews when the host byte order is the profile's; struct otherwise.
        self.native = (sys.byteorder == "little") == self.little
        mv = memoryview(self.mem)
        self.mb = mv.cast("b")
        if self.native:
            self.mw, self.mwu = mv.cast("h"), mv.cast("H")
            self.md, self.mdu = mv.cast("i"), mv.cast("I")
            if self.md.itemsize != 4:   # pragma: no cover - every supported host has a 4-byte C int
                raise RuntimeError("the host C int is not 32 bits")
        order = "<" if self.little else ">"
        self.st_h, self.st_H = struct.Struct(order + "h"), struct.Struct(order + "H")
        self.st_i, self.st_I = struct.Struct(order + "i"), struct.Struct(order + "I")

    def bits(self, kind: str) -> bytearray:
        return getattr(self, kind)

    # ---- operand access functions (used by the machine API, not by generated code)

    def read_mem(self, kind: str, addr: int, signed: bool = True) -> int:
        size = MEM_WIDTH[kind]
        self._check_mem(kind, addr)
        return int.from_bytes(self.mem[addr:addr + size], "little" if self.little else "big", signed=signed)

    def write_mem(self, kind: str, addr: int, value: int) -> None:
        size = MEM_WIDTH[kind]
        self._check_mem(kind, addr)
        value &= (1 << (8 * size)) - 1
        self.mem[addr:addr + size] = value.to_bytes(size, "little" if self.little else "big")

    def _check_mem(self, kind: str, addr: int) -> None:
        size = MEM_WIDTH[kind]
        if addr < 0 or addr + size > self.mem_size:
            raise ValueError(f"{kind}{addr} is outside the byte memory (0..{self.mem_size - 1})")
        if addr % size:
            raise ValueError(f"{kind}{addr} is not aligned to {size} bytes")

    def read(self, kind: str, addr: int) -> int | str:
        """Operand value: bits 0/1, B/W/D sign-extended, S text."""
        if kind in BIT_SPACES:
            return self.bits(kind)[self._bit_index(kind, addr)]
        if kind in MEM_WIDTH:
            return self.read_mem(kind, addr)
        if kind == "S":
            return self.S[self._string_index(addr)]
        raise ValueError(f"no operand kind {kind!r}")

    def write(self, kind: str, addr: int, value: int | str) -> None:
        """Operand write: bits take 0/1 (any true value is 1), B/W/D are truncated to their width, S text to 128 characters."""
        if kind in BIT_SPACES:
            self.bits(kind)[self._bit_index(kind, addr)] = 1 if value else 0
            if kind == "I":
                self.process_inputs[addr] = 1 if value else 0
        elif kind in MEM_WIDTH:
            self.write_mem(kind, addr, int(value))
        elif kind == "S":
            self.S[self._string_index(addr)] = str(value)[:self.string_len]
        else:
            raise ValueError(f"no operand kind {kind!r}")

    def _bit_index(self, kind: str, addr: int) -> int:
        if not 0 <= addr < self.sizes[kind]:
            raise ValueError(f"{kind}{addr} is outside the {kind} space (0..{self.sizes[kind] - 1})")
        return addr

    def _string_index(self, addr: int) -> int:
        if not 0 <= addr < len(self.S):
            raise ValueError(f"S{addr} is outside the string memory (0..{len(self.S) - 1})")
        return addr

    # ---- snapshots for the exact re-run of a cycle

    def snapshot(self, reuse: Snapshot | None = None) -> Snapshot:
        """A copy of the memory. It is taken before every cycle's program phase: `reuse`, an earlier snapshot that
        is no longer needed, is overwritten in place instead of allocating new copies."""
        if reuse is None:
            return Snapshot(tuple(bytearray(self.bits(k)) for k in BIT_SPACES), bytearray(self.mem), list(self.S))
        M, I, O, T, C = reuse.bits                      # noqa: E741 - the operand kinds
        M[:] = self.M
        I[:] = self.I
        O[:] = self.O
        T[:] = self.T
        C[:] = self.C
        reuse.mem[:] = self.mem
        reuse.strings[:] = self.S
        return reuse

    def restore(self, snap: Snapshot) -> None:
        for kind, data in zip(BIT_SPACES, snap.bits):
            self.bits(kind)[:] = data
        self.mem[:] = snap.mem
        self.S[:] = snap.strings
