import sys

from rigfem.cli import main

sys.exit(main())
