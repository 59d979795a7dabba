"""The switches of mutant schemata (schema.py): a statement or expression compiled once per mutation, the one to
run chosen by the global `_MUT` (0: the original; PROBE, negative: the original, recording infections)."""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import Ex
from transpiler.exec.stexec.schema import Variant


def calls_impure(node: Any, impure: frozenset[str]) -> bool:
    """Whether the tree under `node` calls a POU named in `impure` (probing must not call it a second time)."""
    if isinstance(node, (n.Call, n.CallStmt)) and node.name.lower() in impure:
        return True
    if isinstance(node, list):
        return any(calls_impure(item, impure) for item in node)
    if isinstance(node, tuple):
        return any(calls_impure(item, impure) for item in node)
    if dataclasses.is_dataclass(node):
        return any(calls_impure(getattr(node, f.name), impure) for f in dataclasses.fields(node) if f.name != "span")
    return False


@dataclasses.dataclass
class _Attempt:
    lines: list
    pre: list[str]
    result: Any


class SwitchCompiler(PouBase):
    """Statements and expressions with mutations: every variant compiled beside the original."""

    def variants_of(self, node: Any) -> Optional[list[Variant]]:
        schema = self.ctx.schema
        return schema.variants.get(id(node)) if schema is not None else None

    def attempt(self, compile_fn: Callable[[], Any]) -> Optional[_Attempt]:
        """Compile apart (own lines, own pending pre-statements); None when the checker rejects it."""
        saved = (self.lines, self.pre, self.cur_span, self.ctx.error)
        errors: list[str] = []
        self.lines, self.pre = [], []
        self.ctx.error = lambda span, message: errors.append(message)
        try:
            result = compile_fn()
            got = _Attempt(self.lines, self.pre, result)
        finally:
            self.lines, self.pre, self.cur_span, self.ctx.error = saved
        return None if errors or (isinstance(result, Ex) and result.ty is T.ERR) else got

    def _reject(self, variant: Variant) -> None:
        self.ctx.schema.unswitched.add(variant.number)

    def switched_stmt(self, s: n.Stmt, variants: list[Variant]) -> None:
        base = self.indent
        compiled: list[tuple[int, list]] = []
        for v in variants:
            self.indent = base + 2
            got = self.attempt(lambda: self.plain_stmt(v.node))
            self.indent = base
            if got is None:
                self._reject(v)
            else:
                compiled.append((v.number, got.lines))
        if not compiled:
            self.plain_stmt(s)
            return
        numbers = [k for k, _ in compiled]
        self.emit(f"if {min(numbers)} <= _MUT <= {max(numbers)}:", s.span)
        self.indent += 1
        for i, (k, lines) in enumerate(compiled):
            self.emit(f"{'if' if i == 0 else 'elif'} _MUT == {k}:", s.span)
            self.lines.extend(lines or [(base + 2, "pass", s.span)])
        self.emit("else:", s.span)
        self.block(lambda: self.plain_stmt(s))
        self.indent -= 1
        self.emit("elif _MUT < 0:", s.span)
        self.block(lambda: self.probe_stmt(s, [v for v in variants if v.number in numbers]))
        self.emit("else:", s.span)
        self.block(lambda: self.plain_stmt(s))

    def block(self, compile_fn: Callable[[], None]) -> None:
        self.indent += 1
        start = len(self.lines)
        compile_fn()
        if len(self.lines) == start:
            self.emit("pass")
        self.indent -= 1

    def probe_stmt(self, s: n.Stmt, variants: list[Variant]) -> None:
        """The original statement, after recording which variants would store another value (a variant of the
        value only) or, for any other variant, that it is reached."""
        impure = self.ctx.schema.impure
        valued = []
        if isinstance(s, n.Assign) and not calls_impure(s, impure):
            valued = [v for v in variants if isinstance(v.node, n.Assign) and v.node.target == s.target
                      and not calls_impure(v.node, impure)]
        got = self.attempt(lambda: self._values(s, valued)) if valued else None
        if got is None or got.lines or got.pre or got.result is None:
            valued = []
        probed = {id(v) for v in valued}
        reached = [v.number for v in variants if id(v) not in probed]
        if reached:
            self.emit(f"_PR({tuple(reached)!r}, None)", s.span)
        if valued:
            value, alternatives = got.result
            alts = ", ".join(f"({v.number}, lambda: {alt.code})" for v, alt in zip(valued, alternatives))
            self.emit(f"_PX({value.code}, ({alts},))", s.span)
        self.plain_stmt(s)

    def _values(self, s: n.Assign, variants: list[Variant]) -> Optional[tuple[Ex, list[Ex]]]:
        """The value the assignment stores and each variant's, as stored (coerced to the target's type)."""
        target = self.lvalue(s.target)
        if target.ty is T.ERR or T.is_aggregate(target.ty):
            return None
        out = []
        for node in [s.value] + [v.node.value for v in variants]:
            value = self.coerce(self.expr(node), target.ty, node.span, "assignment")
            if value is None or value.ty is T.ERR:
                return None
            out.append(value)
        return out[0], out[1:]

    def switched_expr(self, node: n.Expr, compile_fn: Callable[[n.Expr], Ex], variants: list[Variant]) -> Ex:
        """The expression at a condition or selector, choosing its variant by the mutant number."""
        original = compile_fn(node)
        if self.pre or original.ty is T.ERR:
            for v in variants:
                self._reject(v)
            return original
        alternatives: list[tuple[Variant, Ex]] = []
        for v in variants:
            got = self.attempt(lambda: compile_fn(v.node))
            if got is None or got.lines or got.pre or got.result.ty != original.ty:
                self._reject(v)
            else:
                alternatives.append((v, got.result))
        if not alternatives:
            return original
        o = f"({original.code})"
        chain = " else ".join(f"({alt.code}) if _MUT == {v.number}" for v, alt in alternatives) + f" else {o}"
        numbers = [v.number for v, _ in alternatives]
        impure = self.ctx.schema.impure
        if calls_impure(node, impure) or any(calls_impure(v.node, impure) for v, _ in alternatives):
            probe = f"_PR({tuple(numbers)!r}, {o})"
        else:
            probe = "_PX(" + o + ", (" + ", ".join(f"({v.number}, lambda: ({alt.code}))"
                                                 for v, alt in alternatives) + ",))"
        code = f"(({chain}) if {min(numbers)} <= _MUT <= {max(numbers)} else {o} if _MUT >= 0 else {probe})"
        wrapped = original.wrapped and all(alt.wrapped for _, alt in alternatives)
        return Ex(code, original.ty, wrapped=wrapped)

    def case_swaps(self, s: n.Case, var: str, variants: list[Variant]) -> None:
        """Exchange the selector's two values of each swap variant before the branches are chosen."""
        swaps = [v for v in variants if v.swap is not None]
        if not swaps:
            return
        self.emit("if _MUT:", s.span)
        self.indent += 1
        for i, v in enumerate(swaps):
            a, b = v.swap
            self.emit(f"{'if' if i == 0 else 'elif'} _MUT == {v.number}:", s.span)
            self.indent += 1
            self.emit(f"if {var} == {a}: {var} = {b}")
            self.emit(f"elif {var} == {b}: {var} = {a}")
            self.indent -= 1
        self.emit("elif _MUT < 0:", s.span)
        self.indent += 1
        for v in swaps:
            a, b = v.swap
            self.emit(f"if {var} == {a} or {var} == {b}: _PR(({v.number},), None)")
        self.indent -= 2
