"""``python -m tca_casadi.cli``: the ``tca-casadi`` program."""
import sys

from .run import main

sys.exit(main())
