"""``python -m isolator.cli``: the ``isolator`` command."""

import sys

from isolator.cli.app import main

sys.exit(main())
