"""Packaging hook: the wheel carries templates/ and runtime_shim/ (kept at the repository's top level, one copy)
inside the package as transpiler/_data/, where transpiler/resources.py finds them at run time. Everything else
is in pyproject.toml."""

from pathlib import Path
import shutil

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
# What the installed tool reads: the templates (ST, TwinCAT project files, the output README) and the shim's C
# sources (not its tests, Makefile or build/).
DATA = {"templates": ("st/*.j2", "twincat/*.j2", "readme/*.j2"), "runtime_shim": ("*.c", "*.h")}


class BuildPyWithData(build_py):
    def run(self):
        super().run()
        # An editable install runs from the checkout, where resources.py finds the folders themselves.
        if getattr(self, "editable_mode", False):
            return
        for folder, patterns in DATA.items():
            for pattern in patterns:
                for source in sorted((ROOT / folder).glob(pattern)):
                    target = Path(self.build_lib) / "transpiler" / "_data" / folder / source.relative_to(ROOT / folder)
                    target.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(source, target)


setup(cmdclass={"build_py": BuildPyWithData})
