"""``python -m handsim.cli`` runs the ``handsim`` command."""

import sys

from handsim.cli import main

sys.exit(main())
