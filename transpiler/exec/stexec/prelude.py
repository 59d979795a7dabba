"""The IEC standard function blocks (timers, edge triggers, counters, bistables) written in ST for the executor.

Behaviour follows the IEC 61131-3 definitions as matiec's library implements them: a timer starts on a rising
edge of IN seen by a call, reads the clock once per call (`__CURRENT_TIME`, the simulated time of the current
cycle), and its output appears on the first call at which START + PT <= now. CTU/CTD/CTUD count rising edges.
"""

from __future__ import annotations

_TIMERS = """
FUNCTION_BLOCK TP
  VAR_INPUT IN : BOOL; PT : TIME; END_VAR
  VAR_OUTPUT Q : BOOL; ET : TIME; END_VAR
  VAR STATE : SINT; PREV_IN : BOOL; START_TIME : TIME; END_VAR
  IF STATE = 0 AND NOT PREV_IN AND IN THEN
    STATE := 1; Q := TRUE; START_TIME := __CURRENT_TIME;
  ELSIF STATE = 1 THEN
    IF START_TIME + PT <= __CURRENT_TIME THEN
      STATE := 2; Q := FALSE; ET := PT;
    ELSE
      ET := __CURRENT_TIME - START_TIME;
    END_IF;
  END_IF;
  IF STATE = 2 AND NOT IN THEN
    ET := T#0s; STATE := 0;
  END_IF;
  PREV_IN := IN;
END_FUNCTION_BLOCK

FUNCTION_BLOCK TON
  VAR_INPUT IN : BOOL; PT : TIME; END_VAR
  VAR_OUTPUT Q : BOOL; ET : TIME; END_VAR
  VAR STATE : SINT; PREV_IN : BOOL; START_TIME : TIME; END_VAR
  IF STATE = 0 AND NOT PREV_IN AND IN THEN
    STATE := 1; Q := FALSE; START_TIME := __CURRENT_TIME;
  ELSIF NOT IN THEN
    ET := T#0s; Q := FALSE; STATE := 0;
  ELSIF STATE = 1 THEN
    IF START_TIME + PT <= __CURRENT_TIME THEN
      STATE := 2; Q := TRUE; ET := PT;
    ELSE
      ET := __CURRENT_TIME - START_TIME;
    END_IF;
  END_IF;
  PREV_IN := IN;
END_FUNCTION_BLOCK

FUNCTION_BLOCK TOF
  VAR_INPUT IN : BOOL; PT : TIME; END_VAR
  VAR_OUTPUT Q : BOOL; ET : TIME; END_VAR
  VAR STATE : SINT; PREV_IN : BOOL; START_TIME : TIME; END_VAR
  IF STATE = 0 AND PREV_IN AND NOT IN THEN
    STATE := 1; START_TIME := __CURRENT_TIME;
  ELSIF IN THEN
    ET := T#0s; STATE := 0;
  ELSIF STATE = 1 THEN
    IF START_TIME + PT <= __CURRENT_TIME THEN
      STATE := 2; ET := PT;
    ELSE
      ET := __CURRENT_TIME - START_TIME;
    END_IF;
  END_IF;
  Q := IN OR STATE = 1;
  PREV_IN := IN;
END_FUNCTION_BLOCK
"""

_EDGES = """
FUNCTION_BLOCK R_TRIG
  VAR_INPUT CLK : BOOL; END_VAR
  VAR_OUTPUT Q : BOOL; END_VAR
  VAR M : BOOL; END_VAR
  Q := CLK AND NOT M;
  M := CLK;
END_FUNCTION_BLOCK

FUNCTION_BLOCK F_TRIG
  VAR_INPUT CLK : BOOL; END_VAR
  VAR_OUTPUT Q : BOOL; END_VAR
  VAR M : BOOL; END_VAR
  Q := NOT CLK AND NOT M;
  M := NOT CLK;
END_FUNCTION_BLOCK

FUNCTION_BLOCK SR
  VAR_INPUT S1 : BOOL; R : BOOL; END_VAR
  VAR_OUTPUT Q1 : BOOL; END_VAR
  Q1 := S1 OR (NOT R AND Q1);
END_FUNCTION_BLOCK

FUNCTION_BLOCK RS
  VAR_INPUT S : BOOL; R1 : BOOL; END_VAR
  VAR_OUTPUT Q1 : BOOL; END_VAR
  Q1 := NOT R1 AND (S OR Q1);
END_FUNCTION_BLOCK
"""

_COUNTERS = """
FUNCTION_BLOCK CTU{sfx}
  VAR_INPUT CU : BOOL; R : BOOL; PV : {ty}; END_VAR
  VAR_OUTPUT Q : BOOL; CV : {ty}; END_VAR
  VAR CU_T : R_TRIG; END_VAR
  CU_T(CLK := CU);
  IF R THEN
    CV := 0;
  ELSIF CU_T.Q AND CV < PV THEN
    CV := CV + 1;
  END_IF;
  Q := CV >= PV;
END_FUNCTION_BLOCK

FUNCTION_BLOCK CTD{sfx}
  VAR_INPUT CD : BOOL; LD : BOOL; PV : {ty}; END_VAR
  VAR_OUTPUT Q : BOOL; CV : {ty}; END_VAR
  VAR CD_T : R_TRIG; END_VAR
  CD_T(CLK := CD);
  IF LD THEN
    CV := PV;
  ELSIF CD_T.Q AND CV > 0 THEN
    CV := CV - 1;
  END_IF;
  Q := CV <= 0;
END_FUNCTION_BLOCK

FUNCTION_BLOCK CTUD{sfx}
  VAR_INPUT CU : BOOL; CD : BOOL; R : BOOL; LD : BOOL; PV : {ty}; END_VAR
  VAR_OUTPUT QU : BOOL; QD : BOOL; CV : {ty}; END_VAR
  VAR CD_T : R_TRIG; CU_T : R_TRIG; END_VAR
  CD_T(CLK := CD);
  CU_T(CLK := CU);
  IF R THEN
    CV := 0;
  ELSIF LD THEN
    CV := PV;
  ELSIF NOT (CU_T.Q AND CD_T.Q) THEN
    IF CU_T.Q AND CV < PV THEN
      CV := CV + 1;
    ELSIF CD_T.Q AND CV > 0 THEN
      CV := CV - 1;
    END_IF;
  END_IF;
  QU := CV >= PV;
  QD := CV <= 0;
END_FUNCTION_BLOCK
"""


def prelude_text() -> str:
    counters = "".join(_COUNTERS.format(sfx=sfx, ty=ty) for sfx, ty in
                       (("", "INT"), ("_DINT", "DINT"), ("_LINT", "LINT"), ("_UDINT", "UDINT"), ("_ULINT", "ULINT")))
    return _EDGES + _TIMERS + counters
