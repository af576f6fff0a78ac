"""``python -m bayestribo.cli``: the command line."""

import sys

from bayestribo.cli.main import main

sys.exit(main())
