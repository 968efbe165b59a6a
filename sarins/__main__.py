"""``python -m sarins ...`` = the ``sarins`` command."""
import sys

from sarins.cli import main

sys.exit(main())
