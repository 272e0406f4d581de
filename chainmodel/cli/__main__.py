"""``python -m chainmodel.cli``: the ``chainmodel`` command (as ``python -m chainmodel``)."""

import sys

from . import main

sys.exit(main())
