"""``python -m gpmotion``: the gpmotion command."""
import sys

from .cli import main

sys.exit(main())
