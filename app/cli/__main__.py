"""``python -m app.cli``: the same as the ``handbench`` command."""

import sys

from app.cli.parser import main

sys.exit(main())
