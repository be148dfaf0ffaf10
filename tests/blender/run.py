"""Run the Blender tests: blender -b --factory-startup --python-exit-code 1 -P tests/blender/run.py

Arguments after `--` go to pytest (e.g. `-- -k roles -x`). Exits with pytest's status.
"""

import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
extra = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
sys.exit(pytest.main([HERE, "-p", "no:cacheprovider", "-ra", *extra]))
