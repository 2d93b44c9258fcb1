"""``python -m doe_calib`` is ``doe-calib``."""
import sys

from doe_calib.cli import main

sys.exit(main())
