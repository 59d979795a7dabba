"""Coverage marks: the arrays the generated code writes while it runs with coverage, and what they stand for."""

from __future__ import annotations

import itertools

from transpiler.exec.interp.compile import CompiledProgram


class CoverageMarks:
    """The marks of one machine, shared by its program variants (the fast code and the exact code that re-runs a
    cycle): `ops` has one mark per op (the exact variant), `branches` one per branch slot (both variants: their
    slots are the same), `stretches` one per straight-line stretch of the fast variant. A mark costs the generated
    code one item store; marks become ops and branch outcomes only when coverage is read."""

    def __init__(self, compiled: CompiledProgram):
        self.op_count = len(compiled.op_index)
        self.branch_slots = compiled.branch_slots
        self.branch_ops = compiled.branch_ops
        self.stretch_ops = compiled.stretch_ops
        # Lists of 0/1: an item store into a list is the cheapest store there is (the interpreter specializes it),
        # and count(0) is a fast scan (0 is one object), for branch_outcome_count after every cycle.
        self.ops = [0] * self.op_count
        self.branches = [0] * len(self.branch_slots)
        self.stretches = [0] * len(self.stretch_ops)
        self.value_slots = compiled.value_slots
        self.values = [0] * len(self.value_slots)
        self.bound_slots = compiled.bound_slots
        self.bounds = [0] * len(self.bound_slots)
        # MC/DC: every distinct (condition vector, outcome) of every decision, as one int key (compile.py) in a dict
        # used as an ordered set, so that the vectors a rolled-back cycle recorded can be taken out again.
        self.decision_count = compiled.decision_count
        self.decision_shift = compiled.decision_shift
        self.vectors: dict[int, int] = {}

    def arrays_for(self, compiled: CompiledProgram) -> tuple[list[int], list[int], list[int], list[int], list[int],
                                                             dict[int, int]]:
        """The (ops, branches, stretches, values, bounds, vectors) arrays `compiled` writes into; it must be a variant
        of the same program, and its stretches and value slots (if any) the ones these marks were made for."""
        if len(compiled.op_index) != self.op_count or compiled.branch_slots != self.branch_slots or (
                compiled.bound_slots != self.bound_slots or compiled.decision_count != self.decision_count):
            raise ValueError("coverage marks of another program")
        if compiled.stretch_ops and compiled.stretch_ops != self.stretch_ops:
            raise ValueError("coverage marks made for the stretches of another variant")
        if compiled.value_slots and compiled.value_slots != self.value_slots:
            raise ValueError("coverage marks made for the value profile of another variant")
        return (self.ops, self.branches, self.stretches if compiled.stretch_ops else [], self.values, self.bounds,
                self.vectors)

    def executed(self) -> set[int]:
        """Op ids marked as executed, by their own mark, their stretch's or a branch mark of their stretch's exit."""
        executed = {opid for opid, mark in enumerate(self.ops) if mark}
        for ops, mark in zip(self.stretch_ops, self.stretches):
            if mark:
                executed.update(ops)
        for ops, mark in zip(self.branch_ops, self.branches):
            if mark:
                executed.update(ops)
        return executed

    def branch_outcomes(self) -> frozenset[tuple[int, int]]:
        """The distinct (op id, outcome) pairs marked so far."""
        return frozenset(slot for slot, mark in zip(self.branch_slots, self.branches) if mark)

    def branch_outcome_count(self) -> int:
        """How many distinct (op id, outcome) pairs are marked (it only grows)."""
        return len(self.branches) - self.branches.count(0)

    def value_outcomes(self) -> frozenset[tuple[int, int]]:
        """The distinct (op id, outcome) pairs of the value profile marked so far (compile.value_slots)."""
        return frozenset(slot for slot, mark in zip(self.value_slots, self.values) if mark)

    def value_outcome_count(self) -> int:
        return len(self.values) - self.values.count(0)

    def boundary_outcomes(self) -> frozenset[tuple[int, int]]:
        """The distinct (op id, left - right) of word compares marked so far (compile.boundary_slots)."""
        return frozenset(slot for slot, mark in zip(self.bound_slots, self.bounds) if mark)

    def boundary_outcome_count(self) -> int:
        return len(self.bounds) - self.bounds.count(0)

    def decision_vectors(self) -> dict[int, frozenset[int]]:
        """Decision number -> the distinct vectors recorded (bit i = condition i, the bit above them the outcome)."""
        mask = (1 << self.decision_shift) - 1
        found: dict[int, set[int]] = {}
        for key in self.vectors:
            found.setdefault(key & mask, set()).add(key >> self.decision_shift)
        return {k: frozenset(v) for k, v in found.items()}

    def vector_count(self) -> int:
        return len(self.vectors)

    def vectors_since(self, count: int) -> list[tuple[int, int]]:
        """(decision number, vector) of the vectors recorded after the first `count`, in recording order."""
        mask = (1 << self.decision_shift) - 1
        return [(key & mask, key >> self.decision_shift) for key in itertools.islice(self.vectors, count, None)]

    def forget_vectors_after(self, count: int) -> None:
        """Take out the vectors recorded after the first `count` (a cycle rolled back for its exact re-run)."""
        for key in list(self.vectors)[count:]:
            del self.vectors[key]
