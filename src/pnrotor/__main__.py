import sys

from pnrotor.cli import main

sys.exit(main())
