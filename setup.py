"""Build hook: ship the standard circuits as package data.

The top-level ``circuits/`` directory is the project's fixed layout (README, netlists/ and the
tests refer to it); an installed wheel has no checkout around it, so ``build_py`` copies
``circuits/*.toml`` into ``analogue/circuits/`` of the build.  One source of truth: nothing to
keep in sync by hand.  ``analogue.circuit.experiments`` looks there first, then in the
checkout (a source tree or an editable install has no ``analogue/circuits/``).
"""
from pathlib import Path
import shutil

from setuptools import setup
from setuptools.command.build_py import build_py as _build_py

HERE = Path(__file__).resolve().parent


class build_py(_build_py):
    def run(self):
        super().run()
        source = HERE / "circuits"
        if self.editable_mode or not source.is_dir():  # editable: the checkout is used directly
            return
        target = Path(self.build_lib) / "analogue" / "circuits"
        target.mkdir(parents=True, exist_ok=True)
        for path in sorted(source.glob("*.toml")):
            shutil.copyfile(path, target / path.name)


setup(cmdclass={"build_py": build_py})
