"""``python -m motionbits`` = the ``motionbits`` command."""

import sys

from motionbits.cli import main

sys.exit(main())
