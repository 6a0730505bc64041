"""``python -m tca_casadi.cli``: the ``tca-casadi`` program."""
import sys

from .main import main

sys.exit(main())
