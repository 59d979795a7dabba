"""Type-checks the statements and expressions of one POU and translates them into Python source lines.

PouCompiler is assembled from parts of one job each (pou_base: state and helpers; gen_values: literals and
coercion; gen_access: designators; gen_operators; gen_statements; gen_loops; gen_init: initial values); calls
are compiled by stdlib, which sits below this module."""

from __future__ import annotations

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.gen_access import AccessCompiler
from transpiler.exec.stexec.gen_init import InitCompiler
from transpiler.exec.stexec.gen_loops import LoopCompiler
from transpiler.exec.stexec.gen_operators import OperatorCompiler
from transpiler.exec.stexec.gen_statements import StatementCompiler
from transpiler.exec.stexec.gen_values import ValueCompiler
from transpiler.exec.stexec.pycode import Ex
from transpiler.exec.stexec.stdlib import compile_call, compile_call_stmt


class PouCompiler(StatementCompiler, LoopCompiler, InitCompiler, OperatorCompiler, AccessCompiler, ValueCompiler):
    """Compiles one POU body (or stand-alone initialisers when pou is None)."""

    def expr(self, node: n.Expr, allow_fb: bool = False) -> Ex:
        if isinstance(node, n.Lit):
            return self.literal(node)
        if isinstance(node, n.Name):
            ex = self.name_ex(node)
        elif isinstance(node, n.Addr):
            ex = self.addr_ex(node)
        elif isinstance(node, n.Field):
            ex = self.field_ex(node)
        elif isinstance(node, n.Index):
            ex = self.index_ex(node)
        elif isinstance(node, n.Call):
            return compile_call(self, node)
        elif isinstance(node, n.Unary):
            return self.unary(node)
        elif isinstance(node, n.Binary):
            return self.binary(node)
        else:
            return self.err(self.cur_span, f"unsupported expression {type(node).__name__}")
        if isinstance(ex.ty, T.FbT) and not allow_fb:
            return self.err(node.span, f"function block instance '{ex.var.name if ex.var else '?'}' used as a value")
        return ex

    def s_callstmt(self, s: n.CallStmt) -> None:
        compile_call_stmt(self, s)
