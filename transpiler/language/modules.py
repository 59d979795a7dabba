"""The PLC module catalogue by number (the rows themselves are data in module_table.py)."""

from __future__ import annotations

from transpiler.language.module_table import MODULE_TABLE, Module, nearest

MODULES = MODULE_TABLE
"""Every module number hh2iec knows -> its row (parameters, results, errors, context, kind)."""

__all__ = ["MODULES", "Module", "nearest"]
