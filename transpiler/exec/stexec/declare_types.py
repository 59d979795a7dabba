"""Type declarations: TYPE blocks and the type specifications of variables (arrays, subranges, STRING)."""

from __future__ import annotations

from typing import Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.compiler_base import CompilerBase


class TypeDeclarer(CompilerBase):
    """Type declarations: TYPE blocks and the type specifications of variables (arrays, subranges, STRING)."""

    def resolve_spec(self, spec: n.TypeSpec, ordinal: int, owner: str = "") -> tuple[T.Type, Optional[n.Init]]:
        if isinstance(spec, n.NamedTypeSpec):
            key = spec.name.lower()
            if key in T.ELEMENTARY:
                return T.ELEMENTARY[key], None
            if key in T.UNSUPPORTED_ELEMENTARY:
                self.error(spec.span, f"type {spec.name.upper()} is not supported by the built-in executor")
                return T.ERR, None
            entry = self.ctx.types.get(key)
            if entry is not None:
                if entry[2] >= ordinal:
                    self.error(spec.span, f"type '{spec.name}' is used before its declaration")
                    return T.ERR, None
                return entry[0], entry[1]
            pou = self.ctx.pous.get(key)
            if pou is not None and pou.kind == "function_block":
                if pou.ordinal >= ordinal:
                    self.error(spec.span, f"function block '{spec.name}' is used before its declaration")
                    return T.ERR, None
                return pou.fbtype, None
            if pou is not None:
                self.error(spec.span, f"'{spec.name}' is a {pou.kind.replace('_', ' ')}, not a type")
                return T.ERR, None
            self.error(spec.span, f"unknown type '{spec.name}'")
            return T.ERR, None
        if isinstance(spec, n.StringSpec):
            self.error(spec.span, "STRING[n] is rejected by matiec (it parses, then every use fails); use STRING")
            return T.ERR, None
        if isinstance(spec, n.SubrangeSpec):
            b = T.ELEMENTARY.get(spec.base.lower())
            if b is None or b.cat != "int":
                self.error(spec.span, f"a subrange needs an integer base type, not {spec.base}")
                return T.ERR, None
            if not (b.lo <= spec.lo <= spec.hi <= b.hi):
                self.error(spec.span, f"invalid subrange {spec.lo}..{spec.hi} of {b}")
                return T.ERR, None
            return T.SubrangeT(b, spec.lo, spec.hi), None
        if isinstance(spec, n.ArraySpec):
            for lo, hi in spec.ranges:
                if lo > hi:
                    self.error(spec.span, f"empty array range {lo}..{hi}")
                    return T.ERR, None
            elem, _ = self.resolve_spec(spec.elem, ordinal)
            if isinstance(elem, T.ArrayT):
                self.error(spec.span, "ARRAY OF ARRAY is not supported by matiec; use ARRAY[a..b, c..d]")
                return T.ERR, None
            if isinstance(elem, T.FbT):
                self.error(spec.span, "arrays of function block instances are rejected by matiec")
                return T.ERR, None
            if elem is T.ERR:
                return T.ERR, None
            dims = ", ".join(f"{lo}..{hi}" for lo, hi in spec.ranges)
            return T.ArrayT(owner or f"ARRAY[{dims}] OF {elem}", list(spec.ranges), elem), None
        raise AssertionError(spec)

    def declare_type(self, decl: n.TypeDecl, ordinal: int) -> None:
        key = decl.name.lower()
        if not self.check_name(decl.name, decl.span, False, "type"):
            return
        if key in self.ctx.types or key in self.ctx.pous or key in T.ELEMENTARY:
            self.error(decl.span, f"'{decl.name}' is declared twice")
            return
        spec = decl.spec
        init = decl.init
        if isinstance(spec, n.StructSpec):
            fields: dict[str, T.StructField] = {}
            for el in spec.elems:
                fty, finit = self.resolve_spec(el.spec, ordinal + 1)
                if isinstance(fty, T.FbT):
                    self.error(el.span, "function block instances inside a STRUCT are rejected by matiec")
                    fty = T.ERR
                if el.name.lower() in fields:
                    self.error(el.span, f"field '{el.name}' is declared twice")
                    continue
                fields[el.name.lower()] = T.StructField(el.name, fty, el.init if el.init is not None else finit)
            ty: T.Type = T.StructT(decl.name, fields, "S_" + key)
            self.structs.append(ty)
        elif isinstance(spec, n.EnumSpec):
            values = [v for v, _s in spec.values]
            seen = set()
            for v, vspan in spec.values:
                if v.lower() in seen:
                    self.error(vspan, f"enum value '{v}' is declared twice")
                seen.add(v.lower())
            ety = T.EnumT(decl.name, values)
            if spec.default is not None:
                idx = ety.index(spec.default)
                if idx is None:
                    self.error(spec.span, f"'{spec.default}' is not a value of {decl.name}")
                else:
                    ety.default = idx
            for i, v in enumerate(values):
                self.ctx.enum_values.setdefault(v.lower(), []).append((ety, i))
            ty = ety
        else:
            ty, named_init = self.resolve_spec(spec, ordinal + 1, owner=decl.name)
            if isinstance(ty, T.SubrangeT) and isinstance(spec, n.SubrangeSpec):
                ty.name = decl.name
            if init is None:
                init = named_init
            if isinstance(ty, T.FbT):
                self.error(decl.span, "a TYPE cannot name a function block")
                ty = T.ERR
        self.ctx.types[key] = (ty, init, ordinal)
