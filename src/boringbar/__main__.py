"""``python -m boringbar``: the ``boringbar`` command."""

import sys

from boringbar.cli import main

sys.exit(main())
