"""Compiles the Soar engine's hot modules with mypyc: ``python setup.py build_ext --inplace``
(``make`` does it) puts C extension modules beside their sources, which Python then imports
first. The package's metadata is in pyproject.toml; installing it (``pip install -e .``)
compiles nothing. See sann/soar/compiled.py for when the compiled modules are not used.
"""

import importlib.util
import sys
from pathlib import Path

from setuptools import setup

ROOT = Path(__file__).resolve().parent


def _compiled_module():
    """sann/soar/compiled.py on its own (the package may not be importable yet)."""
    spec = importlib.util.spec_from_file_location("_sann_compiled", ROOT / "sann/soar/compiled.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


if "build_ext" in sys.argv:
    from mypyc.build import mypycify

    compiled = _compiled_module()
    hashes = compiled.source_hashes()  # of the sources as they are compiled
    compiled.MANIFEST.unlink(missing_ok=True)
    sources = [str(compiled.source_file(name).relative_to(ROOT)) for name in compiled.MODULES]
    setup(ext_modules=mypycify(sources, opt_level="3", group_name=compiled.GROUP))
    compiled.write_manifest(hashes)
else:
    setup()
