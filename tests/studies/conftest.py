"""Makes the studies' shared test helpers (``hostile_cli``) importable from every study's
test folder."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
