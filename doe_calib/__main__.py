"""``python -m doe_calib`` is ``doe-calib``."""
import sys

from .cli import main

sys.exit(main())
