"""``python -m boringbar``: the ``boringbar`` command."""

import sys

from boringbar.cli.main import main

sys.exit(main())
