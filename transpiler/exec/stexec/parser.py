"""Parses Structured Text source into the executor's syntax tree (lark LALR, contextual lexer)."""

from __future__ import annotations

import functools
import pathlib
from types import MappingProxyType
from typing import Any

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from transpiler.diagnostics import Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec.errors import StError, st_diag

_GRAMMAR = pathlib.Path(__file__).with_name("grammar.lark")


@functools.lru_cache(maxsize=1)
def _lark() -> Lark:
    # The parser tables are built once per process; Lark objects are read-only after construction.
    return Lark(_GRAMMAR.read_text(encoding="utf-8"), parser="lalr", lexer="contextual",
                propagate_positions=True, maybe_placeholders=True)


class _BuildError(Exception):
    def __init__(self, span: Span, message: str):
        super().__init__(message)
        self.span = span
        self.message = message


def _int_text(text: str) -> int:
    return int(text.replace("_", ""))


@v_args(meta=True)
class _ToNodes(Transformer):
    """Turns the lark tree into nodes; each callback receives meta (positions) and children."""

    def __init__(self, filename: str):
        super().__init__()
        self.filename = filename

    def _span(self, meta: Any) -> Span:
        if getattr(meta, "empty", True):
            return Span(self.filename, 1, 1)
        return Span(self.filename, meta.line, meta.column, meta.end_line, meta.end_column)

    def _tspan(self, tok: Token) -> Span:
        return Span(self.filename, tok.line, tok.column, tok.end_line or tok.line, tok.end_column or tok.column)

    # ---------------------------------------------------------------- file
    def start(self, meta, items):
        return n.SourceFile(list(items), self.filename)

    # ---------------------------------------------------------------- types
    def type_block(self, meta, items):
        return n.TypeBlock(list(items), self._span(meta))

    def type_decl(self, meta, items):
        name, body = items
        spec, init = body
        return n.TypeDecl(str(name), spec, init, self._span(meta))

    def spec_init(self, meta, items):
        return (items[0], items[1])

    def struct_spec(self, meta, items):
        return (n.StructSpec(list(items), self._span(meta)), None)

    def enum_spec(self, meta, items):
        default = items[-1]
        values = [(str(t), self._tspan(t)) for t in items[:-1]]
        return (n.EnumSpec(values, str(default) if default is not None else None, self._span(meta)), None)

    def struct_elem(self, meta, items):
        name, spec, init = items
        return n.StructElem(str(name), spec, init, self._span(meta))

    def named_type(self, meta, items):
        return n.NamedTypeSpec(str(items[0]), self._span(meta))

    def string_len(self, meta, items):
        if str(items[0]).lower() != "string":
            raise _BuildError(self._span(meta), f"'{items[0]}[...]' is not a type (only STRING takes a length)")
        return n.StringSpec(_int_text(items[1]), self._span(meta))

    def subrange_type(self, meta, items):
        return n.SubrangeSpec(str(items[0]), items[1], items[2], self._span(meta))

    def array_type(self, meta, items):
        return n.ArraySpec(list(items[:-1]), items[-1], self._span(meta))

    def range(self, meta, items):
        return (items[0], items[1])

    def pos_int(self, meta, items):
        return _int_text(items[0])

    def neg_int(self, meta, items):
        return -_int_text(items[0])

    def array_init(self, meta, items):
        return n.ArrayInit(list(items), self._span(meta))

    def struct_init(self, meta, items):
        return n.StructInit(list(items), self._span(meta))

    def single_elem(self, meta, items):
        return (None, items[0])

    def repeat_elem(self, meta, items):
        return (_int_text(items[0]), items[1])

    def field_init(self, meta, items):
        return (str(items[0]), items[1], self._span(meta))

    # ---------------------------------------------------------------- POUs
    def _pou(self, kind, meta, name, result, rest):
        blocks = [b for b in rest if isinstance(b, n.VarBlock)]
        body = rest[-1]
        end = Span(self.filename, meta.end_line, meta.end_column) if not getattr(meta, "empty", True) else self._span(meta)
        return n.Pou(kind, str(name), result, blocks, body, self._span(meta), end)

    def function(self, meta, items):
        return self._pou("function", meta, items[0], items[1], items[2:])

    def function_block(self, meta, items):
        return self._pou("function_block", meta, items[0], None, items[1:])

    def program(self, meta, items):
        return self._pou("program", meta, items[0], None, items[1:])

    def var_block(self, meta, items):
        kind = items[0]
        quals = [q for q in items[1:] if isinstance(q, str)]
        decls = [d for d in items[1:] if isinstance(d, n.VarDecl)]
        return n.VarBlock(kind, "constant" in quals, "retain" in quals, decls, self._span(meta))

    def global_block(self, meta, items):
        quals = [q for q in items if isinstance(q, str)]
        decls = [d for d in items if isinstance(d, n.VarDecl)]
        return n.GlobalBlock(n.VarBlock("global", "constant" in quals, "retain" in quals, decls, self._span(meta)))

    def k_var(self, meta, items): return "var"
    def k_input(self, meta, items): return "input"
    def k_output(self, meta, items): return "output"
    def k_inout(self, meta, items): return "inout"
    def k_external(self, meta, items): return "external"
    def k_temp(self, meta, items): return "temp"
    def k_global(self, meta, items): return "global"
    def q_constant(self, meta, items): return "constant"
    def q_retain(self, meta, items): return "retain"
    def q_non_retain(self, meta, items): return "non_retain"

    def plain_decl(self, meta, items):
        names = [(str(t), self._tspan(t)) for t in items[:-2]]
        return n.VarDecl(names, items[-2], items[-1], None, self._span(meta))

    def located_decl(self, meta, items):
        name, addr, spec, init = items
        names = [(str(name), self._tspan(name))] if name is not None else []
        return n.VarDecl(names, spec, init, str(addr), self._span(meta))

    # ---------------------------------------------------------------- configuration
    def configuration(self, meta, items):
        name = str(items[0])
        globals_ = [g.block for g in items[1:] if isinstance(g, n.GlobalBlock)]
        resources = [r for r in items[1:] if isinstance(r, n.Resource)]
        return n.Configuration(name, globals_, resources, self._span(meta))

    def resource(self, meta, items):
        return self._resource(meta, str(items[0]), items[2:])

    def bare_resource(self, meta, items):
        return self._resource(meta, "", items)

    def _resource(self, meta, name, items):
        return n.Resource(name,
                          [g.block for g in items if isinstance(g, n.GlobalBlock)],
                          [t for t in items if isinstance(t, n.Task)],
                          [p for p in items if isinstance(p, n.ProgramConf)],
                          self._span(meta))

    def task(self, meta, items):
        return n.Task(str(items[0]), list(items[1:]), self._span(meta))

    def task_param(self, meta, items):
        return (str(items[0]), items[1], self._span(meta))

    def program_conf(self, meta, items):
        _qual, name, task, type_name, args = items
        return n.ProgramConf(str(name), str(task) if task is not None else None, str(type_name),
                             args is not None, self._span(meta))

    # ---------------------------------------------------------------- statements
    def stmt_list(self, meta, items):
        return list(items)

    def assign_stmt(self, meta, items):
        return n.Assign(items[0], items[1], self._span(meta))

    def call_stmt(self, meta, items):
        return n.CallStmt(str(items[0]), items[1] or [], self._span(meta))

    def if_stmt(self, meta, items):
        branches = [(items[0], items[1])]
        for part in items[2:-1]:
            branches.append(part)
        return n.If(branches, items[-1], self._span(meta))

    def elsif_part(self, meta, items):
        return (items[0], items[1])

    def else_part(self, meta, items):
        return items[0]

    def case_stmt(self, meta, items):
        return n.Case(items[0], list(items[1:-1]), items[-1], self._span(meta))

    def case_elem(self, meta, items):
        return (list(items[:-1]), items[-1])

    def label_int(self, meta, items):
        return n.CaseLabel(items[0], items[0], None, self._span(meta))

    def label_range(self, meta, items):
        return n.CaseLabel(items[0], items[1], None, self._span(meta))

    def label_enum(self, meta, items):
        return n.CaseLabel(None, None, str(items[0]), self._span(meta))

    label_typed = label_enum     # `Mode#Run`: the code generator splits off and checks the type name

    def for_stmt(self, meta, items):
        var, start, end, step, body = items
        return n.For(str(var), self._tspan(var), start, end, step, body, self._span(meta))

    def while_stmt(self, meta, items):
        return n.While(items[0], items[1], self._span(meta))

    def repeat_stmt(self, meta, items):
        return n.Repeat(items[0], items[1], self._span(meta))

    def exit_stmt(self, meta, items):
        return n.Exit(self._span(meta))

    def return_stmt(self, meta, items):
        return n.Return(self._span(meta))

    def continue_stmt(self, meta, items):
        return n.Continue(self._span(meta))

    # ---------------------------------------------------------------- expressions
    def _bin(op):  # noqa: N805 - a factory evaluated in the class body
        def build(self, meta, items):
            return n.Binary(op, items[0], items[1], self._span(meta))
        return build

    or_ = _bin("OR")
    xor_ = _bin("XOR")
    and_ = _bin("AND")
    eq = _bin("=")
    ne = _bin("<>")
    lt = _bin("<")
    gt = _bin(">")
    le = _bin("<=")
    ge = _bin(">=")
    add = _bin("+")
    sub = _bin("-")
    mul = _bin("*")
    div = _bin("/")
    mod = _bin("MOD")
    pow = _bin("**")

    def neg(self, meta, items):
        return n.Unary("-", items[0], self._span(meta))

    def pos(self, meta, items):
        return items[0]

    def not_(self, meta, items):
        return n.Unary("NOT", items[0], self._span(meta))

    def int_lit(self, meta, items):
        return n.Lit("int", str(items[0]), self._span(meta))

    def based_lit(self, meta, items):
        return n.Lit("based", str(items[0]), self._span(meta))

    def real_lit(self, meta, items):
        return n.Lit("real", str(items[0]), self._span(meta))

    def typed_lit(self, meta, items):
        return n.Lit("typed", str(items[0]), self._span(meta))

    def string_lit(self, meta, items):
        return n.Lit("string", str(items[0]), self._span(meta))

    def call(self, meta, items):
        return n.Call(str(items[0]), items[1] or [], self._span(meta))

    def var_name(self, meta, items):
        return n.Name(str(items[0]), self._span(meta))

    def var_addr(self, meta, items):
        return n.Addr(str(items[0]), self._span(meta))

    def var_field(self, meta, items):
        return n.Field(items[0], str(items[1]), self._span(meta))

    def var_index(self, meta, items):
        return n.Index(items[0], list(items[1:]), self._span(meta))

    def arg_list(self, meta, items):
        return list(items)

    def named_arg(self, meta, items):
        return n.Arg(str(items[0]), items[1], None, False, self._span(meta))

    def out_arg(self, meta, items):
        return n.Arg(str(items[0]), None, items[1], False, self._span(meta))

    def not_out_arg(self, meta, items):
        return n.Arg(str(items[0]), None, items[1], True, self._span(meta))

    def pos_arg(self, meta, items):
        return n.Arg(None, items[0], None, False, self._span(meta))


_TOKEN_TEXT = MappingProxyType({
    "SEMICOLON": "';'", "COLON": "':'", "COMMA": "','", "LPAR": "'('", "RPAR": "')'", "LSQB": "'['",
    "RSQB": "']'", "EQUAL": "'='", "LESSTHAN": "'<'", "MORETHAN": "'>'", "PLUS": "'+'", "MINUS": "'-'",
    "STAR": "'*'", "SLASH": "'/'", "DOT": "'.'", "AMPERSAND": "'&'", "IDENT": "a name", "INTEGER": "an integer",
    "REAL_LIT": "a real literal", "BASED_INT": "a based integer", "TYPED_LITERAL": "a typed literal",
    "STRING_LIT": "a string", "DIRECT_ADDR": "a direct address", "ENUM_LABEL": "a CASE label", "$END": "end of file",
})


def _describe(name: str) -> str:
    if name in _TOKEN_TEXT:
        return _TOKEN_TEXT[name]
    try:
        pattern = _lark().get_terminal(name).pattern
        if pattern.type == "str":
            return f"'{pattern.value}'"
    except KeyError:
        pass
    return name


def _syntax_message(err: UnexpectedInput, text: str) -> str:
    if isinstance(err, UnexpectedCharacters):
        ch = text[err.pos_in_stream] if err.pos_in_stream < len(text) else ""
        if ch == "{":
            return "pragmas '{...}' are not supported (matiec pastes them into C)"
        if text.startswith("//", err.pos_in_stream) or text.startswith("/*", err.pos_in_stream):
            return "only (* ... *) comments are allowed in IEC 61131-3 ST"
        if ch == "#":
            return "a based or typed literal is not allowed here (CASE labels must be plain decimal integers)"
        if ch == '"':
            return "double-quoted strings (WSTRING) are not supported"
        return f"unexpected character {ch!r}"
    if isinstance(err, UnexpectedToken):
        tok = err.token
        if tok.type == "$END":
            found = "end of file"
        else:
            found = f"'{tok}'"
        at = tok.start_pos if tok.start_pos is not None else 0
        if text.startswith("(*", at) or (tok.type == "STAR" and at > 0 and text[at - 1] == "("):
            return "unterminated comment '(*'"
        if text.startswith("//", at) or text.startswith("/*", at):
            return "only (* ... *) comments are allowed in IEC 61131-3 ST"
        expected = sorted({_describe(e) for e in err.expected if not e.startswith("__")})
        if len(expected) > 8:
            expected = expected[:8] + ["..."]
        return f"syntax error: unexpected {found}; expected {', '.join(expected)}"
    if isinstance(err, UnexpectedEOF):
        return "syntax error: unexpected end of file"
    return f"syntax error: {err}"


def parse(text: str, filename: str) -> n.SourceFile:
    """Parse a whole ST file; raises StError (E-ST-PARSE) with line and column on bad input."""
    try:
        tree = _lark().parse(text)
    except UnexpectedInput as err:
        line = getattr(err, "line", 1) or 1
        col = getattr(err, "column", 1) or 1
        if isinstance(err, UnexpectedToken) and err.token.type == "$END":
            line = text.count("\n") + 1
            col = len(text) - (text.rfind("\n") + 1) + 1
        raise StError([st_diag(Span(filename, line, col), _syntax_message(err, text))]) from None
    try:
        return _ToNodes(filename).transform(tree)
    except VisitError as err:
        if isinstance(err.orig_exc, _BuildError):
            raise StError([st_diag(err.orig_exc.span, err.orig_exc.message)]) from None
        raise
