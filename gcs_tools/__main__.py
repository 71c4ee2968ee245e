import sys

from gcs_tools.cli import main

sys.exit(main())
