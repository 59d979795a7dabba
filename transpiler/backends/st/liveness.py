"""Register liveness (LA, WA, SA, X) over the whole program, so that accumulators become variables only where a value crosses a block, call or cycle."""

from __future__ import annotations

from types import MappingProxyType

from transpiler.ir import CallTarget, Op, Program
from transpiler.frontend.flow import RoutineBodies, routines_entered, successors

REGS = ("LA", "WA", "SA", "X")
_LA_USE = frozenset({"AND", "ANDN", "OR", "ORN", "XOR", "XORN", "ST", "STN", "SET", "RES", "SETN", "RESN",
                     "JPT", "JPF", "CALLT", "CALLF", "EMT", "EMF", "PSL", "NOTL"})
_LA_DEF = frozenset({"LD", "LDN", "AND", "ANDN", "OR", "ORN", "XOR", "XORN", "CMP", "SCMP", "BT", "PLL", "NOTL"})
_WA_USE = frozenset({"WST", "STBITS", "WAND", "WANDN", "WOR", "WORN", "WXOR", "WXORN", "ADD", "SUB", "MUL", "DIV", "MOD",
                     "CMP", "SHL", "SHR", "BS", "BC", "BT", "PSW", "INCW", "DECW", "NOTW", "TWOC"})
_WA_DEF = frozenset({"WLD", "WLDN", "WNEG", "LDBITS", "WAND", "WANDN", "WOR", "WORN", "WXOR", "WXORN", "ADD", "SUB", "MUL",
                     "DIV", "MOD", "SHL", "SHR", "BS", "BC", "PLW", "INCW", "DECW", "NOTW", "TWOC", "SUBM", "RPLY"})
_SA_USE = frozenset({"SCAT", "SST", "SCMP"})
_SA_DEF = frozenset({"SLD", "SCAT"})
SA_CODES = _SA_USE | _SA_DEF        # the only ops that read or write the string accumulator
_ENDS = frozenset({"EM", "EMT", "EMF"})
_ALL_REGS = frozenset(REGS)
# The data-flow rounds keep a set of registers as a bit mask (one bit per register, in REGS order): a union or
# difference of masks makes no object, and a routine's rounds make one per op and round.
_BIT = MappingProxyType({reg: 1 << n for n, reg in enumerate(REGS)})
_SET_OF_MASK = tuple(frozenset(reg for reg in REGS if mask & _BIT[reg]) for mask in range(1 << len(REGS)))
_ALL_MASK = (1 << len(REGS)) - 1
# The ops whose successors are not just the next op, or that enter routines (flow.successors, routines_entered).
_BRANCHES = frozenset({"EM", "JP", "JPT", "JPF", "CALL", "CALLT", "CALLF", "CASE"})


def use_def(op: Op) -> tuple[frozenset[str], frozenset[str]]:
    """Registers an op reads (before it writes) and registers it certainly writes; calls are handled by the caller."""
    use: set[str] = set()
    d: set[str] = set()
    c = op.code
    if c in _LA_USE:
        use.add("LA")
    if c in _LA_DEF:
        d.add("LA")
    if c in _WA_USE:
        use.add("WA")
    if c in _WA_DEF:
        d.add("WA")
    if c in _SA_USE:
        use.add("SA")
    if c in _SA_DEF:
        d.add("SA")
    if c in ("PSX", "INCX", "DECX"):
        use.add("X")
    if c in ("PLX", "INCX", "DECX"):
        d.add("X")
    if c == "BOPEN":
        use.add("LA" if op.bracket.mode == "LOGIC" else "WA")
    if c == "BCLOSE":
        b = op.bracket
        if b.op in ("==", "<", ">", "<=", ">=", "<>"):
            use.add("WA")
            d.add("LA")
        elif b.mode == "LOGIC":
            use.add("LA")
            d.add("LA")
        else:
            use.add("WA")
            d.add("WA")
    o = op.operand
    if o is not None:
        if o.indexed or o.kind in ("X", "KF"):
            if o.kind == "X" and c == "WST":
                d.add("X")
            else:
                use.add("X")
    return frozenset(use), frozenset(d)


def _mask(regs: frozenset[str]) -> int:
    mask = 0
    for reg in regs:
        mask |= _BIT[reg]
    return mask


class Liveness:
    """The registers live before each op of every routine body (`at`), and at each routine's exit; exit sets solved
    to a fixed point."""

    def __init__(self, program: Program, bodies: RoutineBodies | None = None):
        self.program = program
        bodies = bodies or RoutineBodies.of(program)
        self.main = CallTarget(0, 0, "<main>")
        roots = [self.main] + list(program.routines)
        self.bodies = {r.key: bodies(r) for r in roots}
        self.routines = {r.key: r for r in roots}
        # (register sets as masks, see _BIT)
        self.entry_use: dict[tuple[int, int], int] = dict.fromkeys(self.bodies, 0)
        self.exit_live: dict[tuple[int, int], int] = dict.fromkeys(self.bodies, 0)
        self.live_in: dict[tuple[int, int], dict[int, int]] = {}
        self.fall_into = self._fall_throughs(roots)
        self._use_def: dict[object, tuple[int, int]] = {}
        self._forward: set[tuple[int, int]] = set()     # routines without a backward jump (see _routine)
        # The ops of each routine that call routines, in order, with their callees (a few of its steps; _steps
        # fills it in).
        self.calls: dict[tuple[int, int], list[tuple[int, tuple[tuple[int, int], ...]]]] = {}
        self.steps = {key: self._steps(key, body) for key, body in self.bodies.items()}
        self._solve()

    def _steps(self, key: tuple[int, int], body: list[int]) -> list[tuple]:
        """What the data-flow rounds read of each op of a body, last op first, worked out once instead of in every
        round: (index, use, def, successors or None when only the next op follows, entry keys of the routines it
        calls, whether it ends the routine)."""
        ops = self.program.files[key[0]].ops
        out = []
        calls = []
        forward = True
        for i in reversed(body):
            op = ops[i]
            code = op.code
            # use_def reads only these facts of an op: worked out once per distinct combination (the code alone
            # where the op has no bracket and an operand that reads no index: most ops)
            o = op.operand
            if op.bracket is None and (o is None or not o.indexed and o.kind != "X" and o.kind != "KF"):
                facts = code
            else:
                b = op.bracket
                facts = (code, None if b is None else (b.op, b.mode), None if o is None else (o.kind, o.indexed))
            known = self._use_def.get(facts)
            if known is None:
                use, d = use_def(op)
                known = self._use_def[facts] = (_mask(use), _mask(d))
            use, d = known
            # (successors and routines_entered, for the ops that neither jump nor call: most of them)
            if code not in _BRANCHES:
                out.append((i, use, d, None, (), code in _ENDS))
                continue
            succ = successors(ops, i)
            forward = forward and all(s > i for s in succ)
            callees = tuple(c.key for c in routines_entered(op))
            if callees:
                calls.append((i, callees))
            out.append((i, use, d, succ, callees, code in _ENDS))
        if forward:
            self._forward.add(key)
        calls.reverse()
        self.calls[key] = calls
        return out

    def _fall_throughs(self, roots: list[CallTarget]) -> dict[tuple[int, int], list[tuple[int, int]]]:
        """For each routine, the routines whose entry label its body reaches without a call (falling through or
        jumping there): the structured translation calls them."""
        starts: dict[int, set[int]] = {}        # file -> op indices of its routine entries
        for r in self.program.routines:
            starts.setdefault(r.file, set()).add(r.index)
        found: dict[tuple[int, int], list[tuple[int, int]]] = {}
        for r in roots:
            here = starts.get(r.file, set())
            found[r.key] = [(r.file, i) for i in self.bodies[r.key] if i in here and i != r.index]
        return found

    def _solve(self) -> None:
        # The sets only grow from round to round, so every round that changes something adds one register to one
        # routine's entry or exit set at least: the lattice height bounds the rounds.
        for _ in range(2 * len(self.bodies) * len(REGS) + 2):
            changed = False
            new_exit = dict.fromkeys(self.bodies, 0)
            for key, body in self.bodies.items():
                live = self._routine(key, body)
                self.live_in[key] = live
                entry = live.get(self.routines[key].index, 0)
                if entry != self.entry_use[key]:
                    self.entry_use[key] = entry
                    changed = True
                n_ops = len(self.program.files[key[0]].ops)
                for i, callees in self.calls[key]:
                    for callee in callees:
                        after = live.get(i + 1, 0) if i + 1 < n_ops else 0
                        if callee in new_exit:
                            new_exit[callee] = new_exit[callee] | after
                # The structured translation turns a fall-through into another routine's label into a call of that
                # routine followed by a return: what is live at this routine's exit is live at the callee's exit too.
                for other in self.fall_into[key]:
                    new_exit[other] = new_exit[other] | self.exit_live[key]
            # Registers persist from one cycle to the next: what the main program reads first is live at its end.
            new_exit[self.main.key] = new_exit[self.main.key] | self.entry_use[self.main.key]
            if new_exit != self.exit_live:
                self.exit_live = new_exit
                changed = True
            if not changed:
                return

    def _routine(self, key: tuple[int, int], body: list[int]) -> dict[int, int]:
        exit_live = self.exit_live[key]
        live: dict[int, int] = dict.fromkeys(body, 0)
        entry_use = self.entry_use
        steps = self.steps[key]
        # Without a backward jump, one pass over the ops, last first, sees every successor's final set already.
        for _ in range(1 if key in self._forward else len(body) + 2):
            changed = False
            for i, use, d, succ, callees, ends in steps:
                # use | callees' entry sets | (successors' sets - d)
                out = exit_live if ends else 0
                if succ is None:
                    out |= live.get(i + 1, 0)
                else:
                    for s in succ:
                        out |= live.get(s, 0)
                value = out & ~d | use
                for callee in callees:
                    value |= entry_use.get(callee, 0)
                if value != live[i]:
                    live[i] = value
                    changed = True
            if not changed:
                break
        return live

    def at(self, routine: tuple[int, int], index: int) -> frozenset[str]:
        live = self.live_in.get(routine)
        return _ALL_REGS if live is None else _SET_OF_MASK[live.get(index, _ALL_MASK)]

    def exit(self, routine: tuple[int, int]) -> frozenset[str]:
        return _SET_OF_MASK[self.exit_live.get(routine, _ALL_MASK)]
