"""``python -m chainmodel``: the same command as the ``chainmodel`` console script."""

import sys

from .cli import main

sys.exit(main())
