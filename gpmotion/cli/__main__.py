"""``python -m gpmotion.cli``: the gpmotion command."""
import sys

from . import main

sys.exit(main())
