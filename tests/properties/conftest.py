"""Property tier: make the shared scene strategies (``impact_scenes``) importable whatever
pytest's import mode (the default "prepend" mode does this already; "importlib" does not)."""

import os
import sys

_here = os.path.dirname(os.path.abspath(__file__))
if _here not in sys.path:
    sys.path.insert(0, _here)
