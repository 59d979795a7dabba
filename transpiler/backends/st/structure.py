"""Control-flow structuring: turns jumps of one routine into IF/ELSE, WHILE, REPEAT, EXIT and RETURN, or a state machine when irreducible."""

from __future__ import annotations

import bisect
import dataclasses
from typing import Callable, Sequence

from transpiler.ir import CallTarget, FileCode, Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st.liveness import REGS
from transpiler.backends.st.routine import Unsupported, tag
from transpiler.backends.st.symbolic import Executor

JUMPS = ("JP", "JPT", "JPF")
# The op codes region treats apart from the executor's straight-line code.
_CONTROL = frozenset({"LBL", *JUMPS, "EM", "EMT", "EMF", "CALL", "CALLT", "CALLF", "CASE"})


class NotStructured(Exception):
    """The routine's jumps do not nest; the caller falls back to a state machine."""

    def __init__(self, reason: str, index: int):
        super().__init__(reason)
        self.reason = reason
        self.index = index


@dataclasses.dataclass
class RoutineInfo:
    key: tuple[int, int]
    entry: CallTarget
    file: FileCode
    body: list[int]                 # reachable op indices
    is_main: bool
    call_name: Callable[[CallTarget], str]     # the FB instance that runs a subprogram
    other_entries: dict[int, CallTarget]   # LBLs that start other routines (fall-through -> call + return)
    exit_live: frozenset[str]
    live_in: Callable[[int], frozenset[str]]
    # CM of a routine with a stack interface (see interfaces.py): emits the call and returns True, else False.
    interface_call: Callable[[Op, int, frozenset[str]], bool] | None = None
    # The indices of the file's jumps with a target, in order, where the caller has them (else read from `body`).
    file_jumps: Sequence[int] | None = None


class Structurer:
    """Recursive descent over the textual op order; every region [lo, hi) is entered at lo and left at hi."""

    def __init__(self, info: RoutineInfo, ex: Executor):
        self.info = info
        self.ex = ex
        self.ops = info.file.ops
        self.out = ex.ctx.out
        ordered = sorted(info.body)
        self.body = set(ordered)
        self.last = ordered[-1] if ordered else -1     # the routine's last op
        self.jumps_to: dict[int, list[int]] = {}
        if info.file_jumps is None:
            jumps = [i for i in ordered if self.ops[i].code in JUMPS and self.ops[i].target is not None]
        elif ordered:
            # (the file's jumps within the body's span, of the body: a few, where the body has dozens of ops)
            lo = bisect.bisect_left(info.file_jumps, ordered[0])
            hi = bisect.bisect_right(info.file_jumps, ordered[-1])
            jumps = [i for i in info.file_jumps[lo:hi] if i in self.body]
        else:
            jumps = []
        for i in jumps:
            self.jumps_to.setdefault(self.ops[i].target, []).append(i)
        self.jumps = jumps                          # the body's jumps with a target, in order
        self.entries = sorted(i for i in info.other_entries if i in self.body)   # other routines' entries, in order
        self.loop_exits: list[int] = []    # exit index of each enclosing loop
        self.depth = 0                     # nesting of emitted IF/loop constructs
        self.loop_heads: set[int] = set()  # heads of the loops being emitted (their back edge is the loop itself)

    # ---- helpers

    def _live(self, i: int) -> frozenset[str]:
        return self.info.live_in(i) if i < len(self.ops) else frozenset()

    def _past_labels(self, i: int) -> int:
        """The first op from i on that is not a label or no-op (a label that starts another routine is code: a call)."""
        while i < len(self.ops) and self.ops[i].code in ("LBL", "NOP") and i not in self.info.other_entries:
            i += 1
        return i

    def _is_return_at(self, i: int) -> bool:
        """Control reaching op i returns at once (labels and no-ops, then EM)."""
        i = self._past_labels(i)
        return i < len(self.ops) and self.ops[i].code == "EM"

    def _equiv(self, hi: int) -> set[int]:
        """Targets that behave like reaching `hi`: labels and no-ops fall through, a JP forwards (jump threading)."""
        found = {hi}
        i = hi
        for _ in range(64):
            end = self._past_labels(i)
            found.update(range(i + 1, end + 1))
            i = end
            if i < len(self.ops) and self.ops[i].code == "JP" and self.ops[i].target is not None \
                    and self.ops[i].target > i and self.ops[i].target not in found:
                i = self.ops[i].target
                found.add(i)
                continue
            break
        return found

    def _clean(self, lo: int, hi: int, exit_ok: set[int]) -> bool:
        """No jump from outside [lo, hi) lands strictly inside, and every jump inside stays inside or goes to exit_ok."""
        for t, sources in self.jumps_to.items():
            if lo < t < hi and any(not lo <= s < hi for s in sources):
                return False
        # (the body's jumps and entries in [lo, hi), found by bisection: regions are entered for every IF)
        if bisect.bisect_right(self.entries, lo) < bisect.bisect_left(self.entries, hi):
            return False        # an entry of another routine inside
        jumps = self.jumps
        for i in jumps[bisect.bisect_left(jumps, lo):bisect.bisect_left(jumps, hi)]:
            t = self.ops[i].target
            if not (lo <= t < hi or t in exit_ok or t in self._equiv(hi) or self._is_return_at(t)):
                return False
        return True

    def _return(self, live_exit: frozenset[str]) -> None:
        self.ex.flush(live_exit)
        self.out.add(S.Return())

    def _tag(self, i: int) -> str:
        return tag(self.ops[i].span)

    # ---- regions

    def region(self, lo: int, hi: int) -> None:
        i = lo
        body, ops, jumps_to, other_entries = self.body, self.ops, self.jumps_to, self.info.other_entries
        run = self.ex.run
        while i < hi:
            if i not in body:
                i += 1
                continue
            op = ops[i]
            if op.code not in _CONTROL and i not in jumps_to and i not in other_entries:
                # (most ops: straight-line code for the executor)
                run(op, i)
                i += 1
                continue
            if i != self.info.entry.index and i in other_entries:
                # Falling through into another subprogram's label: call it and return (same effect, readable).
                other = self.info.other_entries[i]
                self.ex.flush(self._live(i))
                self.out.add(S.Call(self.info.call_name(other), note=f"falls through into LBL {other.label}"))
                self.ex.forget()
                self._return(self.info.exit_live)
                return
            if i in self.jumps_to and i not in self.loop_heads and any(s >= i for s in self.jumps_to[i]):
                i = self._loop(i, hi)
                continue
            if op.code == "LBL":
                if i in self.jumps_to:
                    self.ex.flush(self._live(i))
                self.out.comment(f"LBL {op.label}  {op.span.file}:{op.span.line}")
                self.ex.run(op, i)
                i += 1
                continue
            if op.code in JUMPS:
                i = self._forward_jump(i, hi)
                continue
            if op.code in ("EM", "EMT", "EMF"):
                i = self._end(i, hi)
                continue
            if op.code == "CALL" and self.info.interface_call is not None and self.info.interface_call(op, i, self._live(i)):
                i += 1
                continue
            if op.code in ("CALL", "CALLT", "CALLF"):
                self._call(op, i)
                i += 1
                continue
            if op.code == "CASE":
                self._case(op, i)
                i += 1
                continue
            self.ex.run(op, i)
            i += 1

    def _end(self, i: int, hi: int) -> int:
        op = self.ops[i]
        live_exit = self.info.exit_live
        if op.code == "EM":
            self.ex.flush(live_exit)
            last = self.depth == 0 and i >= self.last
            if not last:
                self.out.add(S.Return())
            self.ex.forget()
            return self._skip_dead(i + 1, hi)
        self._if_return(op.code == "EMT", live_exit)
        return i + 1

    def _skip_dead(self, i: int, hi: int) -> int:
        while i < hi and i not in self.body:
            i += 1
        return i

    def _if_return(self, when_la: bool, live: frozenset[str]) -> None:
        # Registers live at the exit reach their variables before the test, on both paths.
        self.ex.keep_live(live)
        self.out.add(S.If(self.ex.la_is(when_la), (S.Return(),)))

    def _call(self, op: Op, i: int) -> None:
        if op.call is None or op.call.file < 0 and not op.call.is_module:
            raise Unsupported("unresolved call", op.span)
        if op.call.is_module:
            # A module call takes its parameters from the data stack and pushes its results (modcalls.py).
            self.ex.index = i
            self.ex.ctx.module_call(self.ex, op, self._live(i))
            return
        self.ex.flush(self._live(i) | frozenset(["LA"] if op.code != "CALL" else []))
        instance = self.info.call_name(op.call)
        if op.code == "CALL":
            self.out.add(S.Call(instance, note=self._tag(i)))
        else:
            self.out.add(S.If(self.ex.la_is(op.code == 'CALLT'), (S.Call(instance),), note=self._tag(i)))
        self.ex.forget()

    def _case(self, op: Op, i: int) -> None:
        self.ex.index = i
        for text in op.comments:
            self.out.comment(text)
        selector = self.ex.value(op.operand)
        self.ex.flush(self._live(i))
        if selector.typ not in ("DINT", "SINT", "INT"):
            selector = E.call(f"{selector.typ}_TO_DINT", [selector], "DINT")
        if not op.case_targets:
            # An empty table calls nothing; 'CASE x OF END_CASE;' is not valid ST (IEC needs at least one case).
            self.out.add(S.Comment(f"CASE {selector.text} without entries: nothing to call", self._tag(i)))
            self.ex.forget()
            return
        branches = []
        for n, target in enumerate(op.case_targets):
            note = op.case_notes[n] if n < len(op.case_notes) else None
            comment = " ".join(note[1]) if note and note[1] else None
            branches.append(S.CaseBranch((n,), (S.Call(self.info.call_name(target), note=comment),)))
        self.out.add(S.Case(selector, tuple(branches), note=self._tag(i)))
        self.ex.forget()

    def _forward_jump(self, i: int, hi: int) -> int:
        op = self.ops[i]
        t = op.target
        if t is None:
            raise NotStructured("jump without target", i)
        if self.loop_exits and t == self.loop_exits[-1]:
            # A jump to the end of the enclosing loop: EXIT.
            if op.code == "JP":
                self.ex.flush(self._live(t))
                self.out.add(S.Exit())
                return self._skip_dead(i + 1, hi)
            # Registers live after the loop or in the rest of the body reach their variables; LA stays
            # symbolic for the test itself.
            self.ex.keep_live(self._live(t) | self._live(i + 1))
            cond = self.ex.la_is(op.code == "JPT")
            self.out.add(S.If(cond, (S.Exit(),)))
            return i + 1
        if t <= i:
            raise NotStructured(f"backward jump to {self.ops[t].label or t} outside a loop", i)
        if t > hi and t in self._equiv(hi):
            t = hi          # reaching the end of this block leads straight to the target
        if self._is_return_at(t) and not (t <= hi and self._clean(i + 1, t, {t})):
            if op.code == "JP":
                self._return(self.info.exit_live)
                return self._skip_dead(i + 1, hi)
            self._if_return(op.code == "JPT", self.info.exit_live)
            return i + 1
        if t > hi:
            raise NotStructured(f"jump to {self.ops[t].label if t < len(self.ops) else 'end'} leaves its block", i)
        if op.code == "JP":
            if not self._clean(i + 1, t, {t}):
                raise NotStructured("jump over code that is entered from elsewhere", i)
            self.ex.flush(self._live(t))
            live_dead = [j for j in range(i + 1, t) if j in self.body]
            if live_dead:
                raise NotStructured("unreachable-looking code that is reachable", i)
            return t
        # IF / ELSE: the skipped block ends with an unconditional forward jump past an else block.
        else_end = None
        last = t - 1
        if last > i and self.ops[last].code == "JP" and self.ops[last].target is not None:
            e = self.ops[last].target
            if (t < e <= hi and self.jumps_to.get(t) == [i] and self._clean(i + 1, last, {last, e})
                    and self._clean(t, e, {e}) and all(s < e for s in self.jumps_to.get(e, []) if s > i)):
                else_end = e
        if else_end is None and not self._clean(i + 1, t, {t}):
            raise NotStructured(f"jumps into or out of the block skipped by {op.mnemonic} at line {op.span.line}", i)
        live_join = self._live(else_end if else_end is not None else t)
        self.ex.keep_live(live_join)
        snap = self.ex.snapshot()
        cond = self.ex.la_is(op.code == "JPF")      # the block runs when the jump is NOT taken
        then_block = self._branch(i + 1, t if else_end is None else last, live_join)
        else_block: list[S.Stmt] = []
        if else_end is not None:
            self.ex.restore(snap)
            else_block = self._branch(t, else_end, live_join)
        self.ex.forget()
        self._emit_if(cond, then_block, else_block, i)
        return else_end if else_end is not None else t

    def _branch(self, lo: int, hi: int, live_join: frozenset[str]) -> list[S.Stmt]:
        """The statements of a branch, built apart (comments waiting before it open it)."""
        self.depth += 1
        try:
            with self.out.nested(comments_before=False) as block:
                self.region(lo, hi)
                self.ex.flush(live_join)
            return block
        finally:
            self.depth -= 1

    def _emit_if(self, cond: E.Expr, then_block: list[S.Stmt], else_block: list[S.Stmt], i: int) -> None:
        if not S.has_code(then_block) and not S.has_code(else_block):
            self.out.block.extend(then_block + else_block)
            return
        if not S.has_code(then_block):
            cond, then_block, else_block = E.b_not(cond), else_block, then_block
        if not S.has_code(else_block):
            then_block, else_block = then_block + else_block, []
        self.out.add(S.If(cond, tuple(then_block), tuple(else_block), note=self._tag(i)))

    def _loop(self, h: int, hi: int) -> int:
        back = [s for s in self.jumps_to[h] if s >= h and s < hi]
        if not back:
            raise NotStructured("loop leaves its block", h)
        j = max(back)
        exit_index = j + 1
        if not self._clean(h, j + 1, {exit_index}):
            raise NotStructured("jumps into the middle of a loop", h)
        if any(s >= h and s != j for s in self.jumps_to[h]):
            raise NotStructured("loop with several back edges", h)
        tail = self.ops[j]
        # Only what the loop reads before writing it enters it in a variable (a WHILE's head condition reads LA,
        # so LA is live there then); a dead accumulator value is not stored.
        self.ex.flush(self._live(h))
        self.ex.index = h
        self.loop_exits.append(exit_index)
        self.loop_heads.add(h)
        try:
            if tail.code in ("JPT", "JPF"):
                self.depth += 1
                with self.out.nested(comments_before=False) as body:
                    self.region(h, j)
                    # The back jump still reads LA: liveness is taken before it.
                    self.ex.index = j - 1
                    self.ex.keep_live(self._live(h) | self._live(exit_index))
                    cond = self.ex.la_is(tail.code == "JPF")     # leave when the back jump is not taken
                self.depth -= 1
                self.ex.forget()
                if not body:
                    # REPEAT needs a statement: one that changes nothing.
                    la = self.ex.ctx.register("LA")
                    body.append(S.Assign(la, E.var(la, "BOOL")))
                self.out.add(S.Repeat(tuple(body), cond, note=self._tag(h)))
                return exit_index
            # Unconditional back jump: a WHILE loop; a conditional exit right at the head becomes its condition.
            head = self.ops[h]
            if head.code in ("JPT", "JPF") and head.target == exit_index:
                cond = self.ex.la_is(head.code == "JPF")
                body = self._branch(h + 1, j, self._live(h) | frozenset(["LA"]))
                self.out.add(S.While(cond, tuple(body), note=self._tag(h)))
                return exit_index
            body = self._branch(h, j, self._live(h))
            self.out.add(S.While(E.bool_const(True), tuple(body), note=self._tag(h)))
            return exit_index
        finally:
            self.loop_exits.pop()
            self.loop_heads.discard(h)


def state_machine(info: RoutineInfo, ex: Executor) -> None:
    """Fallback for irreducible jumps: one CASE branch per basic block inside a WHILE loop (reported)."""
    ops = info.file.ops
    body = sorted(info.body)
    body_set = set(body)
    starts = {info.entry.index}
    for i in body:
        op = ops[i]
        if op.code in JUMPS and op.target is not None:
            starts.add(op.target)
        if op.code in JUMPS + ("EM", "EMT", "EMF"):
            starts.add(i + 1)
    starts = sorted(s for s in starts if s in body_set)
    block_id = {s: n for n, s in enumerate(starts)}
    out = ex.ctx.out
    structurer = Structurer(info, ex)
    all_regs = frozenset(REGS)
    ex.flush(all_regs)
    state = E.var("HH_STATE", "DINT")
    out.add(S.Assign(state.text, E.int_const(block_id[info.entry.index])))
    branches = []
    for n, start in enumerate(starts):
        end = starts[n + 1] if n + 1 < len(starts) else max(body) + 1
        with out.nested(comments_before=False) as block:
            next_state = _state_block(info, ex, structurer, block_id, start, end)
            if next_state is not None:
                out.add(S.Assign(state.text, E.int_const(next_state)))
        branches.append(S.CaseBranch((n,), tuple(block), tag(ops[start].span)))
    running = E.binop(">=", state, E.int_const(0), "BOOL", E.PREC_CMP, 0, 1)
    out.add(S.While(running, (S.Case(state, tuple(branches)),),
                    note="irreducible control flow: one state per basic block"))


def _state_block(info: RoutineInfo, ex: Executor, structurer: Structurer, block_id: dict[int, int], start: int,
                 end: int) -> int | None:
    """The statements of one basic block [start, end) of the state machine; returns the state that follows
    (None when the block chose it itself, -1 when the routine ends)."""
    ops = info.file.ops
    body_set = set(info.body)
    all_regs = frozenset(REGS)
    state = "HH_STATE"
    ex.forget()
    i = start
    while i < end:
        if i not in body_set:
            i += 1
            continue
        op = ops[i]
        if op.code == "JP":
            ex.flush(all_regs)
            return block_id[op.target]
        if op.code in ("JPT", "JPF", "EMT", "EMF"):
            # Conditional jump or return: the taken branch goes to its target (or ends), else fall through.
            ex.flush(all_regs)
            cond = ex.la_is(op.code in ("JPT", "EMT"))
            taken = block_id[op.target] if op.code in ("JPT", "JPF") else -1
            ex.ctx.out.add(S.If(cond, (S.Assign(state, E.int_const(taken)),),
                                (S.Assign(state, E.int_const(block_id.get(i + 1, -1))),)))
            return None
        if op.code == "EM":
            ex.flush(all_regs)
            return -1
        if op.code == "CALL" and info.interface_call is not None and info.interface_call(op, i, structurer._live(i)):
            pass
        elif op.code in ("CALL", "CALLT", "CALLF"):
            structurer._call(op, i)
        elif op.code == "CASE":
            structurer._case(op, i)
        else:
            ex.run(op, i)
        i += 1
    ex.flush(all_regs)
    return block_id.get(end, -1)
