"""``python -m orchestration cosim SYSTEM ...``."""
import sys

from .cli import main

sys.exit(main())
