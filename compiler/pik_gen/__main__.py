"""`python3 -m pik_gen` runs pikg-gen."""
import sys

from pik_gen.cli import main

sys.exit(main())
