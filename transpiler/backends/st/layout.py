"""Data layout: decides the IEC variable of every HEIDENHAIN operand (named BOOL/SINT/INT/DINT variables, or arrays
where overlap or indexing is real), the group of globals it belongs to, and how a POU body names it on the target."""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from types import MappingProxyType

from transpiler.frontend.opcodes import implicit_writes
from transpiler.ir import BIT_KINDS, BYTES, MEM_KINDS, Operand, Program
from transpiler.records import quick_init
from transpiler.backends.st import exprs as E
from transpiler.backends.st.marker_groups import MarkerGroup, Refusal, SymbolicOperand, nonvolatile_ranges, plan_groups
from transpiler.backends.st.dialect import DEFAULT_TARGET, TARGETS, Dialect
from transpiler.backends.st.names import NameTable

# The groups of globals, titled as their sections of the configuration (a GVL target makes lists of them).
GROUP_TITLES = MappingProxyType({"io_in": "Inputs (process image)", "io_out": "Outputs (process image)",
                "nc": "NC interface (NC <-> PLC operands)", "marker": "Markers", "timer": "Timer and counter operands",
                "memory": "Byte memory: bytes, words, double words", "string": "Strings",
                "mp": "Machine parameters (presets in PLC cycles)", "kfield": "Constant fields (KFIELD tables)",
                "register": "Accumulators, index register, data stack", "jobs": "Submit-job queue",
                "data": "PLC data tables (MP_Data.tab, MP_Config.tab)"})
MEM_TYPE = MappingProxyType({"B": "SINT", "W": "INT", "D": "DINT"})
BYTE_ARRAY_TYPE = "T_HH_MEM"
# The op codes implicit_writes may answer for (arithmetic, a closing bracket, a call: a PLC module); any other op
# writes nothing it does not name, and most ops are others.
_MAY_WRITE_IMPLICITLY = frozenset({"MUL", "DIV", "MOD", "ADD", "SUB", "BCLOSE", "CALL", "CALLT", "CALLF"})
BIT_ARRAY_TYPE = "T_HH_BITS_{kind}"
STRING_ARRAY_TYPE = "T_HH_STRINGS"


@quick_init
@dataclasses.dataclass(frozen=True)
class GlobalVar:
    name: str
    type: str
    group: str                      # a key of GROUP_TITLES
    address: str | None = None
    initial: str | None = None
    comment: str | None = None


@quick_init
@dataclasses.dataclass(frozen=True)
class OperandVar:
    """Where one HEIDENHAIN operand lives in the IEC program (a row of io_map.csv)."""

    operand: str                    # e.g. I5, W262
    symbol: str                     # .def symbol or ''
    iec: str                        # variable or element text
    iec_type: str
    direction: str
    comment: str


class Layout:
    """All data decisions of the ST backend; codegen asks it how to read and write each operand."""

    def __init__(self, program: Program, names: NameTable, helper=lambda name: None,
                 dialect: Dialect = TARGETS[DEFAULT_TARGET]):
        self.program = program
        self.names = names
        self.helper = helper
        self.dialect = dialect
        self.profile = program.semantics.profile
        self.little = program.semantics.little_endian
        self.globals: dict[str, GlobalVar] = {}
        # Upper-case names of the 'register' group (accumulators, X, data stack): the variables that saving
        # in-flight values may assign (kept by _add_global, so that the translator need not scan every global).
        self.register_vars: set[str] = set()
        self.rows: list[OperandVar] = []
        self._bit_var: dict[tuple[str, int], str] = {}
        self._mem_var: dict[tuple[str, int], str] = {}
        self._bit_exprs: dict[tuple[str, int], E.Expr] = {}     # bit_lvalue's and read_value's expressions
        self._mem_exprs: dict[tuple[str, int], E.Expr] = {}
        self._constants: dict[int, E.Expr] = {}        # constant's expressions (see constant)
        self._places: dict[str, E.Expr] = {}           # lvalue texts of write_value as expressions (see place)
        self.bit_arrays: dict[str, str] = {}          # kind -> array of the addresses that have no name of their own
        self.bit_access: dict[str, str] = {}          # kind -> accessor FB type for indexed access
        self.mem_array: str | None = None
        self.string_array: str | None = None
        self._string_var: dict[int, str] = {}
        self.types: dict[str, tuple[str, int, int]] = {}   # type name -> (element type, lo, hi)
        # Marker structs (marker_groups.py): the groups, the prefixes refused, each member's group and name, and
        # the fields of each STRUCT type as its members are declared.
        self.marker_groups: tuple[MarkerGroup, ...] = ()
        self.group_refusals: tuple[Refusal, ...] = ()
        self._member: dict[int, tuple[MarkerGroup, str]] = {}
        self.struct_fields: dict[str, list[tuple[str, str]]] = {}   # type name -> (member, comment)
        self._symbols_by_operand = self._symbol_index()
        self._plan()

    # ---- planning

    def _symbol_index(self) -> dict[tuple[str, int], list]:
        index: dict[tuple[str, int], list] = defaultdict(list)
        for sym in sorted(self.program.symbols.values(), key=lambda s: (s.alias_of is not None, s.span.file, s.span.line)):
            if sym.kind != "K":
                index[(sym.kind, sym.addr)].append(sym)
        return index

    def _accesses(self):
        bits: dict[str, set[int]] = defaultdict(set)
        bit_indexed: set[str] = set()
        mem: set[tuple[str, int]] = set()
        mem_indexed = False
        strings: set[int] = set()
        string_indexed = False
        timers: set[int] = set()
        counters: set[int] = set()
        prof = self.profile
        for f in self.program.files:
            for op in f.ops:
                if op.code in _MAY_WRITE_IMPLICITLY:
                    # The error markers (and the module error-code word) the original writes are held and written too.
                    for kind, addr in implicit_writes(op, prof.interface):
                        if kind == "M":
                            bits["M"].add(addr)
                        else:
                            mem.add((kind, addr))
                o = op.operand
                if o is None:
                    continue
                if o.kind in BIT_KINDS:
                    if o.indexed:
                        bit_indexed.add(o.kind)
                    n = op.nbits or 1
                    if n == 1:      # (most bit ops: one bit)
                        bits[o.kind].add(o.addr)
                    else:
                        bits[o.kind].update(range(o.addr, o.addr + n))
                    if o.kind == "T":
                        for a in range(o.addr, o.addr + n):
                            if prof.timer_start[0] <= a <= prof.timer_start[1]:
                                timers.add(a)
                            elif prof.timer_running[0] <= a <= prof.timer_running[1]:
                                timers.add(a - prof.timer_running[0] + prof.timer_start[0])
                    if o.kind == "C":
                        for a in range(o.addr, o.addr + n):
                            for lo, hi in (prof.counter_start, prof.counter_running, prof.counter_release):
                                if lo <= a <= hi:
                                    counters.add(a - lo)
                elif o.kind in MEM_KINDS:
                    if o.indexed:
                        mem_indexed = True
                    else:
                        mem.add((o.kind, o.addr))
                elif o.kind == "S":
                    if o.indexed:
                        string_indexed = True
                    strings.add(o.addr)
        # The operands of the PLC data tables are held (the tables load them) and so is the MP-restart marker,
        # which makes the program load them again.
        for row in self.program.data_rows:
            if row.kind in BIT_KINDS:
                bits[row.kind].add(row.addr)
            elif row.kind == "S":
                strings.add(row.addr)
            else:
                mem.add((row.kind, row.addr))
        if self.program.data_rows and prof.interface.mp_restart is not None:
            bits["M"].add(prof.interface.mp_restart)
        # What the screen masks show is declared as well, though the program may never name it: an HMI binds to it.
        for mask in self.program.masks:
            for field in mask.fields:
                kind, addr = field.ref.kind, field.ref.addr
                if kind in BIT_KINDS:
                    bits[kind].add(addr)
                elif kind in MEM_KINDS:
                    mem.add((kind, addr))
                elif kind == "S":
                    strings.add(addr)
        for t in timers:
            bits["T"].add(t)
            bits["T"].add(t - prof.timer_start[0] + prof.timer_running[0])
        for c in counters:
            bits["C"].update({prof.counter_start[0] + c, prof.counter_running[0] + c, prof.counter_release[0] + c})
        return bits, bit_indexed, mem, mem_indexed, strings, string_indexed, sorted(timers), sorted(counters)

    def _plan(self) -> None:
        bits, bit_indexed, mem, mem_indexed, strings, string_indexed, timers, counters = self._accesses()
        self.timers, self.counters = timers, counters
        if self.program.semantics["marker_structs"]:
            self._plan_marker_groups(bits, mem, strings)
        for kind in "IOMTC":
            if kind in bit_indexed:
                # Indexed access reaches named operands through an accessor FB (a CASE over the named
                # addresses); addresses without a name of their own live in one array.
                size = self.profile.ranges.size(kind)
                tname = BIT_ARRAY_TYPE.format(kind=kind)
                self.types[tname] = ("BOOL", 0, size - 1)
                arr = self.names.name(f"array:{kind}", f"HH_{kind}_other")
                self.bit_arrays[kind] = arr
                self.bit_access[kind] = self.names.name(f"access:{kind}", f"HH_ACCESS_{kind}")
                self._add_global(GlobalVar(arr, tname, "marker",
                                           comment=f"{kind} operands reached only through the index register"))
            for addr in sorted(bits.get(kind, ())):
                self._declare_bit(kind, addr)
        self._plan_memory(mem, mem_indexed)
        if string_indexed:
            size = self.profile.ranges.size("S")
            self.types[STRING_ARRAY_TYPE] = ("STRING", 0, size - 1)
            self.string_array = self.names.name("array:S", "HH_S")
            self._add_global(GlobalVar(self.string_array, STRING_ARRAY_TYPE, "string", comment="string memory (indexed access)"))
            for addr in sorted(strings):
                self._row("S", addr, f"{self.string_array}[{addr}]", "STRING")
        else:
            for addr in sorted(strings):
                self.declare_string(addr)

    def _plan_marker_groups(self, bits: dict[str, set[int]], mem: set[tuple[str, int]], strings: set[int]) -> None:
        """The marker structs, decided before any operand is named: the group and type names are taken first, so
        that a later name that wants one of them is the one renamed (and reported)."""
        roles = {"I": "an input", "O": "an output", "T": "a timer operand", "C": "a counter operand",
                 "B": "a byte", "W": "a word", "D": "a double word", "S": "a string"}
        used = [(kind, addr) for kind in sorted(bits) for addr in sorted(bits[kind])]
        used += sorted(mem) + [("S", addr) for addr in sorted(strings)]
        retained = nonvolatile_ranges(str(self.program.semantics["nonvolatile"]), "M")
        operands = []
        for kind, addr in used:
            syms = self._symbols_by_operand.get((kind, addr))
            if not syms:
                continue
            role = roles.get(kind)
            if kind == "M" and self._is_nc(kind, addr, syms):
                role = "a marker of the NC interface"
            operands.append(SymbolicOperand(kind, addr, syms[0].name, role,
                                            kind == "M" and any(lo <= addr <= hi for lo, hi in retained)))
        symbols = {s.name.upper() for s in self.program.symbols.values()}

        def name_in_use(name: str) -> str | None:
            if self.names.taken(name):
                return "the name of a POU or variable"
            return "a symbol of the program" if name.upper() in symbols else None

        groups, refusals = plan_groups(operands, name_in_use)
        for group in groups:
            self.names.name(f"marker_group:{group.name}", group.name)
            self.names.name(f"type:marker_group:{group.name}", group.type_name)
            for addr, member in group.members:
                self._member[addr] = (group, member)
        self.marker_groups, self.group_refusals = tuple(groups), tuple(refusals)

    def declare_string(self, addr: int) -> str:
        """The variable of string S<addr> in a program without indexed string access, declared (with its row in
        the I/O map) on first use: also for a string that only PLC module calls write."""
        if addr in self._string_var:
            return self._string_var[addr]
        syms = self._symbols_by_operand.get(("S", addr), [])
        name = self.names.name(f"S{addr}", syms[0].name if syms else f"S{addr}")
        self._string_var[addr] = name
        self._add_global(GlobalVar(name, "STRING", "string", comment=self._comment("S", addr)))
        self._row("S", addr, name, "STRING")
        return name

    def _plan_memory(self, mem: set[tuple[str, int]], indexed: bool) -> None:
        # Accesses that share bytes with a differently shaped access must see one byte image.
        intervals = sorted((addr, addr + BYTES[kind], kind) for kind, addr in mem)
        groups: list[list[tuple[int, int, str]]] = []
        for iv in intervals:
            if groups and iv[0] < max(e for _, e, _ in groups[-1]):
                groups[-1].append(iv)
            else:
                groups.append([iv])
        overlapped = [g for g in groups if len({(a, k) for a, _, k in g}) > 1]
        if indexed or overlapped:
            size = self.profile.ranges.size("B")
            self.types[BYTE_ARRAY_TYPE] = ("BYTE", 0, size - 1)
            self.mem_array = self.names.name("array:mem", "HH_MEM")
            why = "indexed access" if indexed else "overlapping B/W/D access"
            self._add_global(GlobalVar(self.mem_array, BYTE_ARRAY_TYPE, "memory",
                                       comment=f"byte memory ({why}; {'little' if self.little else 'big'}-endian words)"))
        array_addrs = set()
        if indexed:
            array_addrs = {(k, a) for k, a in mem}
        else:
            for g in overlapped:
                array_addrs |= {(k, a) for a, _, k in g}
        for kind, addr in sorted(mem, key=lambda t: (t[1], t[0])):
            if (kind, addr) in array_addrs:
                self._row(kind, addr, f"{self.mem_array}[{addr}]", f"{MEM_TYPE[kind]}@{'LE' if self.little else 'BE'}")
            else:
                self._declare_mem(kind, addr)

    def _declare_bit(self, kind: str, addr: int) -> str:
        key = (kind, addr)
        if key in self._bit_var:
            return self._bit_var[key]
        if kind == "M" and addr in self._member:
            return self._declare_member(addr)
        syms = self._symbols_by_operand.get(key, [])
        wanted = syms[0].name if syms else f"{kind}{addr}"
        name = self.names.name(f"{kind}{addr}", wanted)
        self._bit_var[key] = name
        # Inputs and outputs are located in the process image; NC-owned operands get their own list.
        address = {"I": f"%IX{addr // 8}.{addr % 8}", "O": f"%QX{addr // 8}.{addr % 8}"}.get(kind)
        if kind in "IO":
            group = {"I": "io_in", "O": "io_out"}[kind]
        elif self._is_nc(kind, addr, syms):
            group = "nc"
        else:
            group = {"T": "timer", "C": "timer"}.get(kind, "marker")
        self._add_global(GlobalVar(name, "BOOL", group, address=address, comment=self._comment(kind, addr)))
        self._row(kind, addr, name, "BOOL")
        return name

    def _declare_member(self, addr: int) -> str:
        """A marker of a marker struct: its member path; the struct's global comes with its first member."""
        group, member = self._member[addr]
        path = group.path(member)
        self._bit_var[("M", addr)] = path
        if group.name not in self.globals:
            self._add_global(GlobalVar(group.name, group.type_name, "marker",
                                       comment=f"the markers {group.name}_* ({group.addresses()})"))
        self.struct_fields.setdefault(group.type_name, []).append((member, self._comment("M", addr)))
        self._row("M", addr, path, "BOOL")
        return path

    def _declare_mem(self, kind: str, addr: int) -> str:
        key = (kind, addr)
        if key in self._mem_var:
            return self._mem_var[key]
        syms = self._symbols_by_operand.get(key, [])
        name = self.names.name(f"{kind}{addr}", syms[0].name if syms else f"{kind}{addr}")
        self._mem_var[key] = name
        group = "nc" if self._is_nc(kind, addr, syms) else "memory"
        self._add_global(GlobalVar(name, MEM_TYPE[kind], group, comment=self._comment(kind, addr)))
        self._row(kind, addr, name, MEM_TYPE[kind])
        return name

    def _is_nc(self, kind: str, addr: int, syms: list) -> bool:
        if any(s.name.startswith(("NP_", "PN_", "NN_", "PP_")) for s in syms):
            return True
        width = BYTES.get(kind, 1)
        return self.profile.is_interface(kind, addr, width)

    def _comment(self, kind: str, addr: int) -> str:
        syms = self._symbols_by_operand.get((kind, addr), [])
        text = f"{kind}{addr}"
        if syms:
            s = syms[0]
            if s.comment:
                text += f" {s.comment}"
            others = [x.name for x in syms[1:]]
            if others:
                text += f" (also {', '.join(others)})"
        return text

    def _row(self, kind: str, addr: int, iec: str, iec_type: str) -> None:
        syms = self._symbols_by_operand.get((kind, addr), [])
        direction = {"I": "input", "O": "output"}.get(kind, "internal")
        if syms and syms[0].name.startswith("NP_") or (not syms and self.profile.is_interface(kind, addr, BYTES.get(kind, 1))):
            direction = "nc_to_plc" if kind != "O" else direction
        if syms and syms[0].name.startswith("PN_"):
            direction = "plc_to_nc"
        self.rows.append(OperandVar(f"{kind}{addr}", syms[0].name if syms else "", iec, iec_type, direction,
                                    syms[0].comment if syms else ""))

    def _add_global(self, var: GlobalVar) -> None:
        self.globals[var.name] = var
        if var.group == "register":
            self.register_vars.add(var.name.upper())

    def add_register(self, key: str, wanted: str, typ: str, comment: str, initial: str | None = None,
                     group: str = "register") -> str:
        name = self.names.name(key, wanted)
        if name not in self.globals:
            self._add_global(GlobalVar(name, typ, group, initial=initial, comment=comment))
        return name

    def add_data(self, name: str, typ: str, initial: str, comment: str) -> None:
        """A global of the PLC data tables (group `data`): the stored value of one table row."""
        self._add_global(GlobalVar(name, typ, "data", initial=initial, comment=comment))

    # ---- access

    def ref(self, name: str) -> str:
        """How a POU body names the global `name` on the target (`GVL_Markers.name` where lists are qualified); a
        member path (`ML_ax.inpos`) is qualified by the list of its STRUCT global."""
        var = self.globals[name.split(".", 1)[0]]      # (KeyError: not a global, a bug of the caller)
        return self.dialect.reference(name, group_title(var.group)) if self.dialect.qualified_only else name

    def bit_lvalue(self, op: Operand, offset: int = 0) -> E.Expr:
        """The BOOL variable of a (non-indexed) bit operand, offset for LB/B= sequences."""
        key = (op.kind, op.addr + offset)
        known = self._bit_exprs.get(key)
        if known is None:       # (an expression is immutable: one per operand serves every read and write of it)
            name = self._declare_bit(*key)
            text = self.ref(name)
            known = self._bit_exprs[key] = E.Expr(text, "BOOL", frozenset([name.upper(), f"#{op.kind}"]), 0, 1, var=text)
        return known

    def constant(self, value: int) -> E.Expr:
        """A constant operand (K) as its DINT literal: one expression per value serves every read of it."""
        known = self._constants.get(value)
        if known is None:
            known = self._constants[value] = E.int_const(value)
        return known

    def bit_index(self, op: Operand, x: E.Expr, offset: int = 0) -> E.Expr:
        """The operand address of an indexed bit operand (for the accessor FB)."""
        return _index(op.addr + offset, x, 1, self.program.semantics)

    def named_bits(self, kind: str) -> list[tuple[int, str]]:
        return sorted((addr, name) for (k, addr), name in self._bit_var.items() if k == kind)

    def timer_var(self, kind: str, addr: int) -> E.Expr:
        return self.bit_lvalue(Operand(kind, addr))

    def _in_array(self, op: Operand) -> bool:
        """Whether a B/W/D operand lives in the byte array (indexed, or overlapping with a differently shaped access)."""
        return op.indexed or (op.kind, op.addr) not in self._mem_var and self.mem_array is not None

    def read_value(self, op: Operand, x: E.Expr | None) -> E.Expr:
        """A B/W/D operand as a typed expression (SINT/INT/DINT, i.e. sign-extended by type)."""
        if self._in_array(op):
            return self._array_read(op, x)
        key = (op.kind, op.addr)
        known = self._mem_exprs.get(key)
        if known is None:
            known = self._mem_exprs[key] = E.var(self.ref(self._declare_mem(op.kind, op.addr)), MEM_TYPE[op.kind])
        return known

    def place(self, lvalue: str) -> E.Expr:
        """An lvalue text of write_value as the expression a store assigns to (one per text: a place without
        index is written again and again)."""
        known = self._places.get(lvalue)
        if known is None:
            known = self._places[lvalue] = E.var(lvalue, "BYTE")
        return known

    def write_value(self, op: Operand, x: E.Expr | None, value: E.Expr) -> list[tuple[str, E.Expr]]:
        """(lvalue, DINT expression) assignments that store `value` truncated to the operand width."""
        if self._in_array(op):
            return self._array_write(op, x, value)
        name = self._declare_mem(op.kind, op.addr)
        typ = MEM_TYPE[op.kind]
        return [(self.ref(name), _narrow(value, typ))]

    def _byte_index(self, op: Operand, x: E.Expr | None, k: int) -> str:
        size = BYTES[op.kind]
        pos = k if self.little else size - 1 - k          # k = significance of the byte (0 = lowest)
        if op.indexed:
            scale = size if self.program.semantics["index_scaling"] == "elements" else 1
            return _index(op.addr + pos, x, scale, self.program.semantics).text
        return str(op.addr + pos)

    def _array_read(self, op: Operand, x: E.Expr | None) -> E.Expr:
        arr = self.ref(self.mem_array)
        deps = frozenset([self.mem_array.upper()]) | (x.deps if op.indexed and x is not None else frozenset())
        if op.kind == "B":
            return E.Expr(f"BYTE_TO_SINT({arr}[{self._byte_index(op, x, 0)}])", "SINT", deps, -128, 127)
        parts = ", ".join(f"{arr}[{self._byte_index(op, x, k)}]" for k in range(BYTES[op.kind]))
        fn = "HH_MKINT" if op.kind == "W" else "HH_MKDINT"
        self.helper(fn)
        return E.Expr(f"{fn}({parts})", MEM_TYPE[op.kind], deps, *E.RANGES[MEM_TYPE[op.kind]])

    def _array_write(self, op: Operand, x: E.Expr | None, value: E.Expr) -> list[tuple[str, E.Expr]]:
        arr = self.ref(self.mem_array)
        if value.const is not None:
            # a constant's bytes are constants: byte k (0 = lowest) of its two's complement
            return [(f"{arr}[{self._byte_index(op, x, k)}]", _byte_const(value.const >> (8 * k) & 0xFF))
                    for k in range(BYTES[op.kind])]
        if op.kind == "B":
            return [(f"{arr}[{self._byte_index(op, x, 0)}]", E.Expr(f"{value.typ}_TO_BYTE({value.text})", "BYTE", value.deps, 0, 255))]
        self.helper("HH_BYTEOF")
        return [(f"{arr}[{self._byte_index(op, x, k)}]", E.Expr(f"HH_BYTEOF({value.text}, {k})", "BYTE", value.deps, 0, 255))
                for k in range(BYTES[op.kind])]

    def string_lvalue(self, op: Operand, x: E.Expr | None) -> E.Expr:
        if op.indexed:
            index = _index(op.addr, x, 1, self.program.semantics)
            text = f"{self.ref(self.string_array)}[{index.text}]"
            return E.Expr(text, "STRING", frozenset([self.string_array.upper()]) | index.deps, var=text)
        if self.string_array is not None:
            text = f"{self.ref(self.string_array)}[{op.addr}]"
            return E.Expr(text, "STRING", frozenset([self.string_array.upper()]), var=text)
        return E.var(self.ref(self._string_var[op.addr]), "STRING")


def group_title(group: str) -> str:
    """The title of a group of globals (a group without one in GROUP_TITLES is titled with its key)."""
    return GROUP_TITLES.get(group, group)


def _byte_const(value: int) -> E.Expr:
    return E.Expr(str(value), "BYTE", frozenset(), value, value, E.PREC_ATOM, const=value)


def _index(base: int, x: E.Expr | None, scale: int, semantics) -> E.Expr:
    if x is None:
        return E.int_const(base)
    if x.const is not None:
        return E.int_const(base + scale * x.const)
    xs = x if scale == 1 else E.binop("*", x, E.int_const(scale), "DINT", E.PREC_MUL)
    return E.binop("+", E.int_const(base), xs, "DINT", E.PREC_ADD)


def _narrow(value: E.Expr, typ: str) -> E.Expr:
    """Truncate a DINT value to SINT/INT (two's complement, no saturation: A-08)."""
    if value.typ == typ:
        return value
    if value.const is not None:
        bits = {"SINT": 8, "INT": 16, "DINT": 32}[typ]
        v = value.const & ((1 << bits) - 1)
        v = v - (1 << bits) if v >= 1 << (bits - 1) else v
        return E.int_const(v, typ)
    narrow = E.unwiden(value)
    if narrow is not None and narrow.typ == typ and value.typ in ("SINT", "INT", "DINT") and E.fits(value, *E.RANGES[typ]):
        return narrow
    return E.Expr(f"{value.typ}_TO_{typ}({value.text})", typ, value.deps, *E.RANGES[typ],
                  parts=(f"{value.typ}_TO_{typ}", value))
