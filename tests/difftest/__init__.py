"""Differential testing of hh2iec: a seeded generator of random, well-defined HEIDENHAIN PLC projects."""
