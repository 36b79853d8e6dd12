"""``python -m wmiltrack.vot``: the TraX server for the VOT toolkit.

The stable public path of :mod:`wmiltrack.integrations.trax`, where it is defined.
"""

import sys

from .integrations.trax import main, region_to_box, serve

__all__ = ["main", "region_to_box", "serve"]

if __name__ == "__main__":
    sys.exit(main())
