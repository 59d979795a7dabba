"""The random-program generator: deterministic, valid for the front end, and covering every instruction group."""

from __future__ import annotations

import re

from tests.difftest.check import prepare
from tests.difftest.generator import generate

# One mnemonic per instruction group of spec section 6 (6.18 submit jobs and PLC module calls excluded).
GROUPS = {"6.1 load": "LN", "6.2 assign": "SN", "6.3 logic": "XON", "6.5 arithmetic": "MOD", "6.6 compare": "<=",
          "6.7 shift": "<<", "6.8 bit": "BT", "6.9 brackets": "A[", "6.10 stack": "PSW", "6.11 jumps": "JPF",
          "6.12 calls": "CMT", "6.13 index": "=     X", "6.14 extended": "INCW", "6.15 structured": "WHILEF",
          "6.15.1 case": "CASE", "6.16 strings": "S#", "6.17 kfield": "KFIELD"}


def test_same_seed_same_files_and_different_seeds_differ():
    assert generate(7).files == generate(7).files
    assert generate(7).files != generate(8).files


def test_every_instruction_group_occurs():
    text = "\n".join(t for s in range(60) for t in generate(s).files.values()).upper()
    missing = [g for g, m in GROUPS.items() if not re.search(r"(^|\s)" + re.escape(m), text, re.M)]
    assert not missing


def test_generated_projects_pass_the_front_end(tmp_path):
    for seed in range(12):
        project = generate(seed)
        root = tmp_path / str(seed)
        project.write(root)
        prepared = prepare(root / project.main, root / project.cfg if project.cfg else None,
                           root / project.mp if project.mp else None)
        assert not hasattr(prepared, "status"), (seed, prepared)
