"""``python3 -m yggdrasil.view``: see ``yggdrasil.view.cli``."""
import sys

from .cli import main

sys.exit(main())
