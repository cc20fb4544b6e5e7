"""Makes the test suite's own helpers (``fixture_files``) importable from every test folder."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
