"""Every compile-time diagnostic code of the spec: the right code at the right file, line and column, one error per fault."""

from __future__ import annotations

import os

import pytest
from test_frontend_support import Found, compile_files, errors, warnings

from transpiler.diagnostics import CODES, Diagnostics, Severity
from transpiler.frontend.parse import MpParser

# (id, files, expected errors as (code, file, line, col)); the list is the complete error list,
# so every case also checks that one fault gives one error (no cascade).
_MASK_PROGRAM = {"main.src": "#define /g d.def\nL I_a\n= WG_status\nEM\n", "d.def": "I_a I 1\nWG_status W 100\n",
                 "OEM.cfg": ""}
ERROR_CASES = [
    # screen masks beside the main program (docs/masks.md)
    ("mask-syntax", {**_MASK_PROGRAM, "s.msk": '"DIAG\\n"\nCHARSIZE=AUTO;\n'}, [("E-MASK-SYNTAX", "s.msk", 2, 1)]),
    ("mask-undef", {**_MASK_PROGRAM, "s.msk": '" %4D\\n",\n  $WG_stauts$/c;\n'}, [("E-MASK-UNDEF", "s.msk", 2, 3)]),
    ("mask-format", {**_MASK_PROGRAM, "e.a": '"%s\\n", $WG_status$/c;\n'}, [("E-MASK-FORMAT", "e.a", 1, 9)]),
    # preprocessor (spec 3.2, 17b.11: an unclosed #if is reported at the line that opened it)
    ("pp-missing-endif", {"main.src": "L   I1\n#if A = 1\n=   O1\nEM\n", "OEM.cfg": ""}, [("E-PP-NEST", "main.src", 2, 1)]),
    # no configuration at all: one root error at the first #if on an undefined name, not a warning per #if
    ("cfg-missing", {"main.src": '#if CFG_X = "a"\nL I1\n#endif\n#if CFG_Y = 1\n#endif\nEM\n'},
     [("E-CFG-MISSING", "main.src", 1, 1)]),
    ("main-is-module", {"main.src": "GLOBAL Fn\nLBL Fn\nL I_x\n= O1\nEM\n"}, [("E-MAIN-MODULE", "main.src", 1, 1)]),
    ("pp-extra-endif", {"main.src": "L   I1\n  #endif\n=   O1\nEM\n"}, [("E-PP-NEST", "main.src", 2, 3)]),
    ("pp-second-else", {"main.src": "DEFINE A = 1\n#if A = 1\n#else\n#else\n#endif\nEM\n"},
     [("E-PP-NEST", "main.src", 4, 1)]),
    ("pp-else-alone", {"main.src": "EM\n#else\n"}, [("E-PP-NEST", "main.src", 2, 1)]),
    ("pp-malformed-if", {"main.src": "#if = 3\n#endif\nEM\n"}, [("E-PP-SYNTAX", "main.src", 1, 1)]),
    # configuration (17b.3: a bad DEFINE value is an error)
    ("cfg-bad-value", {"main.src": "EM\n", "OEM.cfg": "DEFINE A = 1\nDEFINE B = 1.5\n"}, [("E-CFG-SYNTAX", "OEM.cfg", 2, 1)]),
    ("cfg-no-value", {"main.src": "EM\n", "OEM.cfg": "  DEFINE A =\n"}, [("E-CFG-SYNTAX", "OEM.cfg", 1, 3)]),
    # files
    ("file-uses-missing", {"main.src": "USES missing.src\nEM\n"}, [("E-FILE-NOT-FOUND", "main.src", 1, 1)]),
    ("file-define-missing", {"main.src": "   #define /g missing.def\nEM\n"}, [("E-FILE-NOT-FOUND", "main.src", 1, 4)]),
    ("file-include-missing", {"main.src": "INCLUDE missing.inc\nEM\n"}, [("E-FILE-NOT-FOUND", "main.src", 1, 1)]),
    ("file-dotdot", {"main.src": "USES ../outside.src\nEM\n"}, [("E-FILE-ESCAPE", "main.src", 1, 1)]),
    ("file-dotdot-inside", {"main.src": "USES sub/../../x.src\nEM\n"}, [("E-FILE-ESCAPE", "main.src", 1, 1)]),
    ("file-absolute", {"main.src": "EM\n#define /g /etc/passwd\n"}, [("E-FILE-ESCAPE", "main.src", 2, 1)]),
    ("file-backslash-absolute", {"main.src": "USES \\windows\\x.src\nEM\n"}, [("E-FILE-ESCAPE", "main.src", 1, 1)]),
    ("file-drive", {"main.src": "USES C:\\x.src\nEM\n"}, [("E-FILE-ESCAPE", "main.src", 1, 1)]),
    ("file-include-self", {"main.src": "INCLUDE main.src\nEM\n"}, [("E-FILE-INCLUDE-CYCLE", "main.src", 1, 1)]),
    # syntax
    ("syntax-two-operands", {"main.src": "L I1 I2\nEM\n"}, [("E-SYNTAX", "main.src", 1, 6)]),
    ("syntax-indented", {"main.src": "  L   I1   M2\nEM\n"}, [("E-SYNTAX", "main.src", 1, 12)]),
    ("syntax-no-operand", {"main.src": "L\nEM\n"}, [("E-SYNTAX", "main.src", 1, 1)]),
    ("syntax-operand-on-em", {"main.src": "L I1\nEM I1\n"}, [("E-SYNTAX", "main.src", 2, 1)]),
    ("syntax-label-without-name", {"main.src": "LBL\nEM\n"}, [("E-SYNTAX", "main.src", 1, 1)]),
    ("syntax-bare-number", {"main.src": "L 12\nEM\n"}, [("E-SYNTAX", "main.src", 1, 1)]),
    ("syntax-module-number", {"main.src": "CM 8000\nEM\n"}, [("E-SYNTAX", "main.src", 1, 1)]),
    ("syntax-kentry-outside", {"main.src": "K5\nEM\n"}, [("E-SYNTAX", "main.src", 1, 1)]),
    ("syntax-endk-alone", {"main.src": "EM\nENDK\n"}, [("E-SYNTAX", "main.src", 2, 1)]),
    ("syntax-kfield-open", {"main.src": "EM\nKFIELD T\nK1\n"}, [("E-SYNTAX", "main.src", 2, 1)]),
    ("syntax-def-line", {"main.src": "#define /g a.def\nEM\n", "a.def": "MG_x Q 5\n"}, [("E-SYNTAX", "a.def", 1, 1)]),
    ("syntax-def-k-without-value", {"main.src": "#define /g a.def\nEM\n", "a.def": "KG_x K\n"}, [("E-SYNTAX", "a.def", 1, 1)]),
    # unsupported constructs (3.5, 3.7, A-16, A-23)
    ("unsupported-macro", {"main.src": "ERROR_MACRO 12\nEM\n"}, [("E-UNSUPPORTED", "main.src", 1, 1)]),
    ("unsupported-macro-like-mnemonic", {"main.src": "  SET_ERROR 5\nEM\n"}, [("E-UNSUPPORTED", "main.src", 1, 3)]),
    ("unsupported-glued", {"main.src": "LM12\nEM\n"}, [("E-UNSUPPORTED", "main.src", 1, 1)]),
    ("syntax-bad-constant-line", {"main.src": "EM\nKFIELD T\nK 5x\nENDK\n"}, [("E-SYNTAX", "main.src", 3, 1)]),
    ("syntax-directive-without-name", {"main.src": "GLOBAL\nEM\n"}, [("E-SYNTAX", "main.src", 1, 1)]),
    ("unsupported-typedef", {"main.src": "#define /g a.def\nEM\n", "a.def": "#TYPEDEF ApiSpin\n"},
     [("E-UNSUPPORTED", "a.def", 1, 1)]),
    ("unsupported-assign-not", {"main.src": "L I1\n=N O1\nEM\n"}, [("E-UNSUPPORTED", "main.src", 2, 1)]),
    # literals (2.5, A-56)
    ("lit-decimal", {"main.src": "L K2147483648\n= D0\nEM\n"}, [("E-LIT-RANGE", "main.src", 1, 1)]),
    ("lit-negative", {"main.src": "L K-2147483649\n= D0\nEM\n"}, [("E-LIT-RANGE", "main.src", 1, 1)]),
    ("lit-hex", {"main.src": "L K$1FFFFFFFF\n= D0\nEM\n"}, [("E-LIT-RANGE", "main.src", 1, 1)]),
    ("lit-binary", {"main.src": "L K%1" + "0" * 32 + "\n= D0\nEM\n"}, [("E-LIT-RANGE", "main.src", 1, 1)]),
    ("lit-kfield", {"main.src": "EM\nKFIELD T\nK99999999999\nENDK\n"}, [("E-LIT-RANGE", "main.src", 3, 1)]),
    ("lit-def", {"main.src": "#define /g a.def\nL KG_big\n= D0\nEM\n", "a.def": "KG_big K 4294967296\n"},
     [("E-LIT-RANGE", "a.def", 1, 1)]),
    # operand kinds (4.1, 6.x)
    ("kind-store-constant", {"main.src": "L K5\n= K6\nEM\n"}, [("E-OPERAND-KIND", "main.src", 2, 1)]),
    ("kind-negate-bit", {"main.src": "L- M1\n= W0\nEM\n"}, [("E-OPERAND-KIND", "main.src", 1, 1)]),
    ("kind-lb-word", {"main.src": "LB W0\n= W0\nEM\n"}, [("E-OPERAND-KIND", "main.src", 1, 1)]),
    ("kind-case-marker", {"main.src": "CASE M1\nCM A\nENDC\nEM\nLBL A\nEM\n"}, [("E-OPERAND-KIND", "main.src", 1, 1)]),
    ("kind-kfield-as-symbol", {"main.src": "L T\n= D0\nEM\nKFIELD T\nK1\nENDK\n"}, [("E-OPERAND-KIND", "main.src", 1, 1)]),
    ("kind-pl-constant", {"main.src": "PS K1\nPL K1\nEM\n"}, [("E-OPERAND-KIND", "main.src", 2, 1)]),
    ("kind-shift-bit", {"main.src": "L W0\n<< M1\n= W0\nEM\n"}, [("E-OPERAND-KIND", "main.src", 2, 1)]),
    ("kind-string-arith", {"main.src": "L S1\n- S2\n= S3\nEM\n"}, [("E-OPERAND-KIND", "main.src", 2, 1)]),
    ("kind-constant-indexed", {"main.src": "#define /g a.def\nL KG_x[X]\n= D0\nEM\n", "a.def": "KG_x K 1\n"},
     [("E-OPERAND-KIND", "main.src", 2, 1)]),
    # address range and alignment (5.2, 17b.2)
    ("range-marker", {"main.src": "L M10000\n= O1\nEM\n"}, [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("range-lb-tail", {"main.src": "LB M9995\n= B0\nEM\n"}, [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("range-word-tail", {"main.src": "L D9998\n= D0\nEM\n"}, [("E-ADDR-ALIGN", "main.src", 1, 1)]),
    ("range-double", {"main.src": "L D10000\n= D0\nEM\n"}, [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("range-string", {"main.src": "L S100\n= S0\nEM\n"}, [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("range-string-ref", {"main.src": "L S#E1000\n= S0\nEM\n"}, [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("range-def", {"main.src": "#define /g a.def\nEM\n", "a.def": "* header\nMG_far M 12000\n"}, [("E-ADDR-RANGE", "a.def", 2, 1)]),
    ("align-word", {"main.src": "   L   W3\nEM\n"}, [("E-ADDR-ALIGN", "main.src", 1, 4)]),
    ("align-double", {"main.src": "L K1\n= D6\nEM\n"}, [("E-ADDR-ALIGN", "main.src", 2, 1)]),
    ("align-def", {"main.src": "#define /g a.def\nEM\n", "a.def": "WG_odd W 3\n"}, [("E-ADDR-ALIGN", "a.def", 1, 1)]),
    # symbols (7.1, 7.2)
    ("sym-undef", {"main.src": "L I1\n= O_undefined\nEM\n"}, [("E-SYM-UNDEF", "main.src", 2, 1)]),
    ("sym-undef-local-scope", {"main.src": "USES m.src\nEXTERN F\nL I_loc\n= O1\nCM F\nEM\n",
                               "m.src": "#define loc.def\nGLOBAL F\nLBL F\nL I_loc\n= O2\nEM\n", "loc.def": "I_loc I 3\n"},
     [("E-SYM-UNDEF", "main.src", 3, 1)]),
    ("sym-undef-kfield", {"main.src": "L KF Nope[X]\n= D0\nEM\n"}, [("E-SYM-UNDEF", "main.src", 1, 1)]),
    ("sym-reserved", {"main.src": "#define /g a.def\nEM\n", "a.def": "MG_ok M 1\nM12 M\nX K 1\nK5 K 5\n"},
     [("E-SYM-RESERVED", "a.def", 2, 1), ("E-SYM-RESERVED", "a.def", 3, 1), ("E-SYM-RESERVED", "a.def", 4, 1)]),
    ("sym-dup", {"main.src": "#define /g a.def\nL A_x\n= O1\nEM\n", "a.def": "A_x M 1\nA_x M 2\n"},
     [("E-SYM-DUP", "a.def", 2, 1)]),
    ("sym-dup-label", {"main.src": "EM\nLBL A\nEM\nLBL A\nEM\n"}, [("E-SYM-DUP-LABEL", "main.src", 4, 1)]),
    ("sym-dup-kfield", {"main.src": "EM\nKFIELD T\nK1\nENDK\nEM\nKFIELD T\nK2\nENDK\n"}, [("E-SYM-DUP-LABEL", "main.src", 6, 1)]),
    ("sym-label-after-kfield", {"main.src": "EM\nKFIELD T\nK1\nENDK\nLBL T\nEM\n"}, [("E-SYM-DUP-LABEL", "main.src", 5, 1)]),
    ("sym-kfield-after-label", {"main.src": "EM\nLBL T\nEM\nKFIELD T\nK1\nENDK\n"}, [("E-SYM-DUP-LABEL", "main.src", 4, 1)]),
    ("sym-global-undef", {"main.src": "USES m.src\nEM\n", "m.src": "GLOBAL Fn\nLBL G\nEM\n"},
     [("E-SYM-GLOBAL-UNDEF", "m.src", 1, 1)]),
    ("sym-unresolved-no-extern", {"main.src": "USES m.src\nCM Fn\nEM\n", "m.src": "GLOBAL Fn\nLBL Fn\nEM\n"},
     [("E-SYM-UNRESOLVED", "main.src", 2, 1)]),
    ("sym-unresolved-no-export", {"main.src": "USES m.src\nEXTERN Fn\nCM Fn\nEM\n", "m.src": "LBL Fn\nEM\n"},
     [("E-SYM-UNRESOLVED", "main.src", 3, 1)]),
    ("sym-unresolved-case-entry", {"main.src": "CASE B0\nCM Nowhere\nENDC\nEM\n"}, [("E-SYM-UNRESOLVED", "main.src", 2, 1)]),
    ("sym-dup-global", {"main.src": "USES a.src\nUSES b.src\nEXTERN Fn\nCM Fn\nEM\n",
                        "a.src": "GLOBAL Fn\nLBL Fn\nEM\n", "b.src": "; b\nGLOBAL Fn\nLBL Fn\nEM\n"},
     [("E-SYM-DUP-GLOBAL", "b.src", 2, 1)]),
    ("def-alias-unknown", {"main.src": "#define /g a.def\nEM\n", "a.def": "I_a M &MG_none\n"}, [("E-DEF-ALIAS", "a.def", 1, 1)]),
    ("def-alias-kind", {"main.src": "#define /g a.def\nEM\n", "a.def": "I_x I 3\nM_a M &I_x\n"}, [("E-DEF-ALIAS", "a.def", 2, 1)]),
    # brackets (6.9)
    ("bracket-balance-open", {"main.src": "L I1\nA[\nL I2\n= O1\nEM\n"}, [("E-BRACKET-BALANCE", "main.src", 2, 1)]),
    ("bracket-balance-close", {"main.src": "L I1\n]\n= O1\nEM\n"}, [("E-BRACKET-BALANCE", "main.src", 2, 1)]),
    ("bracket-mode-logic", {"main.src": "L I1\n+[\nL K1\n]\n= W0\nEM\n"}, [("E-BRACKET-MODE", "main.src", 2, 1)]),
    ("bracket-mode-compare", {"main.src": "L I1\n==[\nL K1\n]\n= O1\nEM\n"}, [("E-BRACKET-MODE", "main.src", 2, 1)]),
    ("bracket-mode-string", {"main.src": "L S\"x\"\nA[\nL I1\n]\n= O1\nEM\n"}, [("E-BRACKET-MODE", "main.src", 2, 1)]),
    ("bracket-span-jump", {"main.src": "L I1\nA[\nJP X1\n]\nLBL X1\nEM\n"}, [("E-BRACKET-SPAN", "main.src", 3, 1)]),
    ("bracket-span-label", {"main.src": "L I1\nA[\nLBL X1\nL I2\n]\n= O1\nEM\n"}, [("E-BRACKET-SPAN", "main.src", 3, 1)]),
    ("bracket-span-ift", {"main.src": "L I1\nA[\nIFT\n]\nENDI\nEM\n"}, [("E-BRACKET-SPAN", "main.src", 3, 1)]),
    ("bracket-span-case", {"main.src": "L W0\n+[\nCASE B0\nCM A\nENDC\n]\nEM\nLBL A\nEM\n"},
     [("E-BRACKET-SPAN", "main.src", 3, 1)]),
    # structured statements (6.15)
    ("struct-else-alone", {"main.src": "ELSE\nEM\n"}, [("E-STRUCT-NEST", "main.src", 1, 1)]),
    ("struct-endw-alone", {"main.src": "L I1\nENDW\nEM\n"}, [("E-STRUCT-NEST", "main.src", 2, 1)]),
    ("struct-until-alone", {"main.src": "L I1\nUNTILT\nEM\n"}, [("E-STRUCT-NEST", "main.src", 2, 1)]),
    ("struct-never-closed", {"main.src": "L I1\nIFT\nL I2\n= O1\nEM\n"}, [("E-STRUCT-NEST", "main.src", 2, 1)]),
    ("struct-two-else", {"main.src": "L I1\nIFT\nELSE\nELSE\nENDI\nEM\n"}, [("E-STRUCT-NEST", "main.src", 4, 1)]),
    ("struct-interleaved", {"main.src": "L I1\nIFT\nWHILET\nENDI\nENDW\nEM\n"}, [("E-STRUCT-NEST", "main.src", 4, 1)]),
    ("struct-too-deep", {"main.src": "L I1\n" + "IFT\n" * 17 + "ENDI\n" * 17 + "EM\n"}, [("E-STRUCT-NEST", "main.src", 18, 1)]),
    # CASE (6.15.1)
    ("case-body-instruction", {"main.src": "CASE B0\nCM A\nL I1\nENDC\nEM\nLBL A\nEM\n"}, [("E-CASE-BODY", "main.src", 3, 1)]),
    ("case-body-module", {"main.src": "CASE B0\nCM 9032\nENDC\nEM\n"}, [("E-CASE-BODY", "main.src", 2, 1)]),
    ("module-unknown", {"main.src": "L I1\n  CMT 9999\nEM\n"}, [("E-MODULE-UNKNOWN", "main.src", 2, 3)]),
    ("case-body-label", {"main.src": "CASE B0\nLBL A\nENDC\nEM\n"}, [("E-CASE-BODY", "main.src", 2, 1)]),
    ("case-never-closed", {"main.src": "L I1\nCASE B0\nCM A\nEM\nLBL A\nEM\n"}, [("E-CASE-BODY", "main.src", 2, 1)]),
    ("case-endc-alone", {"main.src": "ENDC\nEM\n"}, [("E-STRUCT-NEST", "main.src", 1, 1)]),
    # KF placement (6.17), jumps, end of file, calls (6.11, 6.12, 7.3)
    ("kf-placement", {"main.src": "L I1\nKFIELD T\nK1\nENDK\nEM\n"}, [("E-KF-PLACEMENT", "main.src", 2, 1)]),
    ("kf-after-conditional-em", {"main.src": "L I1\nEMT\nKFIELD T\nK1\nENDK\nEM\n"}, [("E-KF-PLACEMENT", "main.src", 3, 1)]),
    ("jump-unknown", {"main.src": "L I1\nJPT Nowhere\nEM\n"}, [("E-JUMP-SCOPE", "main.src", 2, 1)]),
    ("jump-other-file", {"main.src": "USES m.src\nEXTERN F\nJP F\nEM\n", "m.src": "GLOBAL F\nLBL F\nEM\n"},
     [("E-JUMP-SCOPE", "main.src", 3, 1)]),
    ("fall-off-main", {"main.src": "L I1\n= O1\n\n; the end\n"}, [("E-FALL-OFF-END", "main.src", 4, 1)]),
    ("fall-off-module", {"main.src": "USES m.src\nEXTERN F\nCM F\nEM\n", "m.src": "GLOBAL F\nLBL F\nL I1\n= O1\n"},
     [("E-FALL-OFF-END", "m.src", 4, 1)]),
    ("fall-off-conditional", {"main.src": "L I1\nJPT Out\nEM\nLBL Out\nL I2\nEMT\n"}, [("E-FALL-OFF-END", "main.src", 6, 1)]),
    ("recursion-self", {"main.src": "CM A\nEM\nLBL A\nCM A\nEM\n"}, [("E-CALL-RECURSION", "main.src", 4, 1)]),
    ("recursion-mutual-files", {"main.src": "USES m.src\nEXTERN F\nCM F\nEM\nLBL G\nL I1\nCMT F\nEM\nGLOBAL G\n",
                                "m.src": "EXTERN G\nGLOBAL F\nLBL F\nCM G\nEM\n"},
     [("E-CALL-RECURSION", "main.src", 7, 1)]),       # first in file order: main.src before m.src
    ("recursion-case", {"main.src": "CM A\nEM\nLBL A\nCASE B0\nCM B\nENDC\nEM\nLBL B\nCM A\nEM\n"},
     [("E-CALL-RECURSION", "main.src", 5, 1)]),
    ("call-depth", {"main.src": "CM F0\nEM\n" + "".join(f"LBL F{i}\nCM F{i + 1}\nEM\n" for i in range(32)) + "LBL F32\nEM\n"},
     [("E-CALL-DEPTH", "main.src", 1, 1)]),
    # PLC data tables (docs/language.md#plc-data-tables): found beside the main program here
    ("tab-no-end", {"main.src": "#define /g a.def\nEM\n", "a.def": "DG_x D 8\n",
                    "MP_Data.tab": "BEGIN MP_DATA.TAB\nNR NAME VALUE\n0  DG_x 1\n"},
     [("E-TAB-SYNTAX", "MP_Data.tab", 3, 1)]),
    ("tab-symbol", {"main.src": "#define /g a.def\nEM\n", "a.def": "DG_x D 8\nI_y I 1\n",
                    "MP_Config.tab": "BEGIN MP_CONFIG.TAB\nNR NAME VALUE\n0  DG_z 1\n1  I_y  1\n[END]\n"},
     [("E-TAB-SYMBOL", "MP_Config.tab", 3, 4), ("E-TAB-SYMBOL", "MP_Config.tab", 4, 4)]),
    ("tab-value", {"main.src": "#define /g a.def\nEM\n", "a.def": "MG_x M 8\nWG_y W 2\n",
                   "MP_Data.tab": "BEGIN MP_DATA.TAB\nNAME  VALUE\nMG_x  2\nWG_y  70000\n[END]\n"},
     [("E-TAB-VALUE", "MP_Data.tab", 3, 7), ("E-TAB-VALUE", "MP_Data.tab", 4, 7)]),
    ("tab-dup", {"main.src": "#define /g a.def\nEM\n", "a.def": "MG_x M 8\n",
                 "MP_Data.tab": "BEGIN MP_DATA.TAB\nNAME  VALUE\nMG_x  1\n[END]\n",
                 "MP_Config.tab": "BEGIN MP_CONFIG.TAB\nNAME  VALUE\nMG_x  0\n[END]\n"},
     [("E-TAB-DUP", "MP_Config.tab", 3, 1)]),
]

# (id, files, profile, expected errors) for behaviour that depends on the profile
PROFILE_CASES = [
    ("tnc407-gap", {"main.src": "L I40\n= O1\nEM\n"}, "tnc407", [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("tnc407-marker", {"main.src": "L M3100\n= O1\nEM\n"}, "tnc407", [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("tnc407-interface-marker-ok", {"main.src": "L M3168\n= O1\nL M2045\n= O2\nEM\n"}, "tnc407", []),
    ("tnc407-extended", {"main.src": "L I1\nNOTL\n= O1\nEM\n"}, "tnc407", [("E-UNSUPPORTED", "main.src", 2, 1)]),
    ("tnc426-word", {"main.src": "L W4096\n= W0\nEM\n"}, "tnc426", [("E-ADDR-RANGE", "main.src", 1, 1)]),
    ("itnc-interface-word-ok", {"main.src": "L W1022\n= W0\nL W272\n= W2\nEM\n"}, "itnc530", []),
]

# (id, files, expected warnings) — warnings never fail a check
WARNING_CASES = [
    ("pp-undef", {"main.src": "#if NOPE = 1\nL I1\n#endif\nEM\n", "OEM.cfg": "DEFINE B = 1\n"},
     [("E-PP-UNDEF", "main.src", 1, 1)]),
    ("pp-case", {"main.src": "EM\n#if CFG_Panel = 1\n#endif\n", "OEM.cfg": "DEFINE CFG_panel = 1\n"},
     [("E-PP-CASE", "main.src", 2, 1)]),
    ("pp-undef-ref", {"main.src": "DEFINE A = &zzz\nEM\n"}, [("E-PP-UNDEF-REF", "main.src", 1, 1)]),
    ("def-redefine", {"main.src": "DEFINE A = 1\n  DEFINE A = 2\nEM\n"}, [("E-DEF-REDEFINE", "main.src", 2, 3)]),
    ("cfg-free-text", {"main.src": "EM\n", "OEM.cfg": "DEFINE A = 1\nthis line explains something\n"},
     [("E-CFG-IGNORED", "OEM.cfg", 2, 1)]),
    ("mod-unreachable", {"main.src": "USES m.src\nEXTERN Fn\nCM Fn\nEM\n", "m.src": "GLOBAL Fn\nL I1\nLBL Fn\nEM\n"},
     [("E-MOD-UNREACHABLE", "m.src", 2, 1)]),
    ("sym-case", {"main.src": "#define /g a.def\nEM\n", "a.def": "MG_a M 1\nMG_A M 2\n"}, [("E-SYM-CASE", "a.def", 2, 1)]),
    ("def-dup-addr", {"main.src": "#define /g a.def\nEM\n", "a.def": "I_a I 5\nI_b I 5\n"}, [("E-DEF-DUP-ADDR", "a.def", 2, 1)]),
]


def _expected(rows) -> list[Found]:
    return [Found(*row) for row in rows]


@pytest.mark.parametrize("files, profile, expected", [pytest.param(f, "itnc530", e, id=i) for i, f, e in ERROR_CASES]
                         + [pytest.param(f, p, e, id=i) for i, f, p, e in PROFILE_CASES])
def test_error_code_line_and_column(tmp_path, files, profile, expected):
    result = compile_files(tmp_path, files, profile=profile)
    assert errors(result) == _expected(expected), [d.render() for d in result.diagnostics.items]


@pytest.mark.parametrize("files, expected", [pytest.param(f, e, id=i) for i, f, e in WARNING_CASES])
def test_warning_code_line_and_column(tmp_path, files, expected):
    result = compile_files(tmp_path, files)
    assert errors(result) == [], [d.render() for d in result.diagnostics.items]
    assert warnings(result) == _expected(expected)
    assert result.ok


def test_every_compile_time_code_of_the_spec_is_exercised():
    """The cases above cover each compile-time code that the spec and the registry name."""
    covered = {row[0] for _, _, rows in ERROR_CASES + WARNING_CASES for row in rows}
    covered |= {row[0] for _, _, _, rows in PROFILE_CASES for row in rows}
    covered |= {"E-MP-VALUE"}                      # test_mp_value below (MP files are read by the simulator)
    spec_codes = {"E-PP-NEST", "E-PP-UNDEF", "E-PP-UNDEF-REF", "E-DEF-REDEFINE", "E-CFG-SYNTAX", "E-MP-VALUE",
                  "E-FILE-NOT-FOUND", "E-FILE-ESCAPE", "E-SYNTAX", "E-UNSUPPORTED", "E-LIT-RANGE",
                  "E-MOD-UNREACHABLE", "E-OPERAND-KIND", "E-ADDR-RANGE", "E-ADDR-ALIGN", "E-SYM-UNDEF",
                  "E-SYM-RESERVED", "E-SYM-DUP", "E-SYM-CASE", "E-SYM-DUP-LABEL", "E-SYM-GLOBAL-UNDEF",
                  "E-SYM-UNRESOLVED", "E-SYM-DUP-GLOBAL", "E-DEF-DUP-ADDR", "E-BRACKET-DEPTH", "E-BRACKET-BALANCE",
                  "E-BRACKET-MODE", "E-BRACKET-SPAN", "E-STRUCT-NEST", "E-CASE-BODY", "E-KF-PLACEMENT",
                  "E-JUMP-SCOPE", "E-FALL-OFF-END", "E-CALL-RECURSION", "E-CALL-DEPTH", "E-MODULE-UNKNOWN"}
    missing = spec_codes - covered - {"E-BRACKET-DEPTH"}       # test_bracket_depth below
    assert not missing, sorted(missing)
    assert spec_codes <= set(CODES)
    # every front-end code of the registry appears in some case (runtime, scenario and tool codes excepted)
    front_end = {c for c in CODES if not c.startswith(("E-RT-", "E-SIM-", "E-SCENARIO", "E-ST-", "E-TOOL", "E-USAGE",
                                                         "E-XSD", "E-TARGET", "W-LINT", "E-FILE-READ", "E-DEF-POOL",
                                                         "E-MP-AMBIGUOUS", "E-MP-NONE"))}
    # E-DEF-UNUSED, E-WERROR and E-ENCODING need command-line options: tests/test_stranger_frontend.py
    front_end -= {"E-DEF-UNUSED", "E-WERROR", "E-ENCODING"}
    # E-MP-AMBIGUOUS and E-MP-NONE belong to transpile (machine parameters chosen for the translation):
    # tests/test_equiv_verdict.py exercises both. E-MP-TRANSLATION and E-MP-UNREPRESENTABLE are co-simulation's
    # (tests/test_equiv_verdict.py, tests/test_data_tables.py).
    front_end -= {"E-MP-TRANSLATION", "E-MP-UNREPRESENTABLE"}
    # E-SHARD belongs to sharded equiv/mutate and merge: tests/test_shard.py
    front_end -= {"E-SHARD"}
    assert front_end - covered - {"E-BRACKET-DEPTH"} == set()


def test_bracket_depth_once_per_nest(tmp_path):
    """17 nested brackets: one E-BRACKET-DEPTH at the 17th opener; the closers cause nothing more."""
    body = "L I1\n" + "A[\nL I1\n" * 20 + "]\n" * 20 + "= O1\n"
    again = "L I2\n" + "O[\nL I2\n" * 17 + "]\n" * 17 + "= O2\n"
    result = compile_files(tmp_path, {"main.src": body + again + "EM\n"})
    first_line = 1 + 2 * 16 + 1
    second_line = 1 + 40 + 20 + 1 + 1 + 2 * 16 + 1
    assert errors(result) == [Found("E-BRACKET-DEPTH", "main.src", first_line, 1),
                              Found("E-BRACKET-DEPTH", "main.src", second_line, 1)]


def test_sixteen_levels_are_allowed(tmp_path):
    program = ("L I1\n" + "A[\nL I1\n" * 16 + "]\n" * 16 + "= O1\n" + "L I1\n" + "IFT\n" * 16 + "ENDI\n" * 16
               + "CM F0\nEM\n" + "".join(f"LBL F{i}\nCM F{i + 1}\nEM\n" for i in range(31)) + "LBL F31\nEM\n")
    result = compile_files(tmp_path, {"main.src": program})
    assert errors(result) == []
    assert result.program.call_depth == 32


def test_symlink_out_of_the_folder_is_an_escape(tmp_path):
    outside = tmp_path / "outside"
    project = tmp_path / "project"
    outside.mkdir()
    project.mkdir()
    (outside / "o.src").write_text("GLOBAL A\nLBL A\nEM\n")
    os.symlink(outside / "o.src", project / "link.src")
    result = compile_files(project, {"main.src": "USES link.src\nEXTERN A\nCM A\nEM\n"})
    assert errors(result) == [Found("E-FILE-ESCAPE", "main.src", 1, 1)]
    # the same file is fine when its folder is an -I folder, and a symlink inside the folder is fine too
    result = compile_files(project, {}, include_dirs=(outside,))
    assert errors(result) == []
    os.symlink(project / "main.src", project / "alias.src")
    result = compile_files(project, {"top.src": "USES alias.src\nEM\n"}, main="top.src", include_dirs=(outside,))
    assert errors(result) == []


def test_symlinked_folder_out_of_the_project(tmp_path):
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "m.src").write_text("GLOBAL A\nLBL A\nEM\n")
    (tmp_path / "project").mkdir()
    os.symlink(tmp_path / "outside", tmp_path / "project" / "lib")
    result = compile_files(tmp_path / "project", {"main.src": "USES lib/m.src\nEXTERN A\nCM A\nEM\n"})
    assert errors(result) == [Found("E-FILE-ESCAPE", "main.src", 1, 1)]


def test_missing_files_do_not_cascade(tmp_path):
    """A missing module or definition file is one error: its labels and symbols are not reported again."""
    files = {"main.src": "#define /g GLB.DEF\nUSES Missing.src\nEXTERN Fn\nL MG_a\n= MG_b\nCM Fn\nEM\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-FILE-NOT-FOUND", "main.src", 1, 1), Found("E-FILE-NOT-FOUND", "main.src", 2, 1)]
    # once the files exist, a genuinely undefined symbol is reported again
    files.update({"GLB.DEF": "MG_a M 1\n", "Missing.src": "GLOBAL Fn\nLBL Fn\nEM\n"})
    assert errors(compile_files(tmp_path, files)) == [Found("E-SYM-UNDEF", "main.src", 5, 1)]


def test_rejected_definitions_do_not_cascade(tmp_path):
    files = {"main.src": "#define /g a.def\nL MG_far\n= MG_odd\nL WG_odd\n= WG_q\nL KG_big\n= DG_x\nL MG_bad\n"
                         "= MG_alias\nEM\n",
             "a.def": "MG_far M 12000\nWG_odd W 3\nKG_big K 4294967296\nMG_bad Q 1\nMG_alias M &MG_far\n"
                      "WG_q W 10\nDG_x D 20\nMG_odd M 7\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-ADDR-RANGE", "a.def", 1, 1), Found("E-ADDR-ALIGN", "a.def", 2, 1),
                              Found("E-LIT-RANGE", "a.def", 3, 1), Found("E-SYNTAX", "a.def", 4, 1)]


def test_a_rejected_label_line_is_not_reported_again_at_its_uses(tmp_path):
    files = {"main.src": "USES m.src\nEXTERN F\nCM F\nJP Loc\nEM\nLBL Loc Extra\nEM\n",
             "m.src": "GLOBAL F\nLBL F junk\nEM\n"}
    result = compile_files(tmp_path, files)
    assert errors(result) == [Found("E-SYNTAX", "m.src", 2, 7), Found("E-SYNTAX", "main.src", 6, 9)]
    assert warnings(result) == []


def test_independent_faults_are_all_reported_once(tmp_path):
    program = ("L I_undef\n= O1\nL W3\n= W0\nJP Nowhere\nL I1\nA[\nL I2\nEM\n]\n= O3\nL K1\n= K2\n"
               "L I1 I2\nERROR_MACRO\nEM\n")
    result = compile_files(tmp_path, {"main.src": program})
    assert [(e.code, e.line) for e in errors(result)] == [
        ("E-SYM-UNDEF", 1), ("E-ADDR-ALIGN", 3), ("E-JUMP-SCOPE", 5), ("E-BRACKET-SPAN", 9),
        ("E-OPERAND-KIND", 13), ("E-SYNTAX", 14), ("E-UNSUPPORTED", 15)]


def test_syntax_error_on_the_last_em_is_not_also_a_fall_off(tmp_path):
    result = compile_files(tmp_path, {"main.src": "L I1\n= O1\nEMM\n"})
    assert [e.code for e in errors(result)] == ["E-UNSUPPORTED"]     # "'EMM' is neither a mnemonic, ..."
    result = compile_files(tmp_path, {"main.src": "L I1\n= O1\nCASE B_undef\nCM A\nENDC\nEM\nLBL A\nEM\n"})
    assert [e.code for e in errors(result)] == ["E-SYM-UNDEF"]


def test_mp_value(tmp_path):
    diags = Diagnostics()
    lines = ("MP4110.0 : 0.125 ;clamp", "  MP 4110.1:3", "MP4110.2 : fast", "* comment", "", "MP4120 : 12")
    params = MpParser().parse_lines("machine.mp", lines, diags)
    assert [(p.number, p.index, str(p.value)) for p in params] == [(4110, 0, "0.125"), (4110, 1, "3"), (4120, 0, "12")]
    assert [(d.code, d.span.line, d.span.col, d.severity) for d in diags.items] == [("E-MP-VALUE", 3, 1, Severity.ERROR)]
