"""Initial values: the Python expression that builds a fresh value from an ST initialiser."""

from __future__ import annotations

from typing import Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import default_code, py_literal


class InitCompiler(PouBase):
    """Initial values: the Python expression that builds a fresh value from an ST initialiser."""

    def init_code(self, ty: T.Type, init: Optional[n.Init], span: Span) -> str:
        """Python expression that builds a fresh value of type ty with the given initialiser (None: default)."""
        b = T.base(ty)
        if init is None:
            return default_code(ty)
        if isinstance(b, T.ArrayT):
            if not isinstance(init, n.ArrayInit):
                self.err(span, f"an array ({ty}) needs an initialiser in brackets [ ... ]")
                return default_code(ty)
            items: list[str] = []
            for count, item in init.items:
                code = self.init_code(b.elem, item, span) if item is not None \
                    else default_code(b.elem)
                items.extend([code] * (count if count is not None else 1))
            if len(items) > b.size:
                self.err(init.span, f"{len(items)} initial values for an array of {b.size} elements")
                items = items[:b.size]
            rest = b.size - len(items)
            if T.is_aggregate(b.elem):
                items.extend([default_code(b.elem)] * rest)
                return "[" + ", ".join(items) + "]"
            tail = f" + [{default_code(b.elem)}] * {rest}" if rest else ""
            return "[" + ", ".join(items) + "]" + tail
        if isinstance(b, (T.StructT, T.FbT)):
            if not isinstance(init, n.StructInit):
                self.err(span, f"a {ty} needs an initialiser in parentheses ( field := value, ... )")
                return default_code(ty)
            parts = []
            for fname, finit, fspan in init.fields:
                key = fname.lower()
                if isinstance(b, T.StructT):
                    f = b.fields.get(key)
                    fty = f.ty if f is not None else None
                else:
                    fv = b.pou.vars.get(key)
                    fty = fv.ty if fv is not None and fv.kind in ("input", "output", "var") else None
                if fty is None:
                    self.err(fspan, f"{ty} has no field or input '{fname}'")
                    continue
                parts.append(f"v_{key}={self.init_code(fty, finit, fspan)}")
            return f"_sinit({default_code(ty)}, {', '.join(parts)})" if parts else default_code(ty)
        if isinstance(init, (n.ArrayInit, n.StructInit)):
            self.err(span, f"a {ty} cannot take an array or struct initialiser")
            return default_code(ty)
        ex = self.expr(init)
        if ex.ty is T.ERR:
            return default_code(ty)
        ex = self.coerce(ex, ty, init.span, "initial value")
        if ex.ty is T.ERR:
            return default_code(ty)
        if ex.const is None:
            self.err(init.span, "an initial value must be a literal (constant expression)")
            return default_code(ty)
        return py_literal(ex.const)[0]
