"""Emission of the Python module: struct classes, one function or class per POU, the globals class."""

from __future__ import annotations

from typing import Optional

from transpiler.diagnostics import Span
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.codegen import PouCompiler
from transpiler.exec.stexec.compiler_base import CompilerBase
from transpiler.exec.stexec.model import PouInfo, VarInfo
from transpiler.exec.stexec.pycode import Ex, default_code
from transpiler.exec.stexec.pysource import PySource, st_span, storage_class


class PythonEmitter(CompilerBase):
    """Emission of the Python module: struct classes, one function or class per POU, the globals class."""

    def emit_structs(self, src: PySource) -> None:
        for st in self.structs:
            pc = PouCompiler(self.ctx, None, self.ctx.types[st.name.lower()][2] + 1)
            storage_class(src, st.pyname, [(f"v_{k}", pc.init_code(f.ty, f.init, st_span(f, self.filename)), None)
                                            for k, f in st.fields.items()])
            src.add(1, "def _copy(self):")
            src.add(2, f"o = {st.pyname}.__new__({st.pyname})")
            for k, f in st.fields.items():
                src.add(2, f"o.v_{k} = {PouCompiler.copy_code(f.ty, 'self.v_' + k)}")
            src.add(2, "return o")
            src.add(1, "def _set(self, o):")
            for k, f in st.fields.items():
                lines = pc.assign_lines(Ex(f"self.v_{k}", f.ty), Ex(f"o.v_{k}", f.ty))
                for line in lines:
                    src.add(2, line)
            src.add(2, "return self")

    def emit_pou(self, src: PySource, info: PouInfo) -> None:
        pc = PouCompiler(self.ctx, info, info.ordinal)
        header_span = info.node.span
        if info.kind == "function":
            params = ", ".join(f"v_{v.key}" for v in info.pyparams)
            src.add(0, f"def F_{info.key}({params}):", header_span)
            for v in info.vars.values():
                if v.kind in ("output", "var", "temp"):
                    if v.constant and v.const_value is not None:
                        continue
                    src.add(1, f"v_{v.key} = {pc.init_code(v.ty, v.init, v.span)}", v.span)
            src.add(1, f"v_{info.key} = {default_code(info.result) if info.result is not T.ERR else 'None'}",
                    header_span)
            pc.stmts(info.node.body)
            for indent, text, span in pc.lines:
                src.add(indent, text, span)
            src.add(1, pc.return_line(), info.node.end_span)
            return
        storage_class(src, f"C_{info.key}", [(f"v_{v.key}", pc.init_code(v.ty, v.init, v.span), v.span)
                                              for v in info.state_vars], header_span)
        src.add(0, f"def B_{info.key}(self):", header_span)
        for v in info.vars.values():
            if v.kind == "temp":
                src.add(1, f"v_{v.key} = {pc.init_code(v.ty, v.init, v.span)}", v.span)
        pc.stmts(info.node.body)
        for indent, text, span in pc.lines:
            src.add(indent, text, span)

    def emit_globals(self, src: PySource) -> None:
        pc = PouCompiler(self.ctx, None, 1 << 30)
        fields: list[tuple[str, str, Optional[Span]]] = [("now", "0", None)]
        fields += [(f"v_{g.key}", pc.init_code(g.ty, g.init, g.span), g.span)
                   for g in self.ctx.globals.values() if g.location is None]
        inits: dict[str, VarInfo] = {}
        for info in self.ctx.pous.values():
            for v in info.vars.values():
                if v.location is not None and v.init is not None:
                    inits.setdefault(v.location, v)
        for g in self.ctx.globals.values():
            if g.location is not None and g.init is not None:
                inits[g.location] = g
        for addr, (ty, attr, span) in self.locations.items():
            v = inits.get(addr)
            fields.append((attr, pc.init_code(ty, v.init, v.span) if v is not None else default_code(ty), span))
        storage_class(src, "C__G", fields)
