import sys

from viewer.commands.main import main

sys.exit(main())
