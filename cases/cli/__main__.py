"""``python -m cases.cli``: the ``penetrate`` command."""

import sys

from . import main

sys.exit(main())
