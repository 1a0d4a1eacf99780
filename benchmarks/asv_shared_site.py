"""Let an asv environment (``asv.conf.json``'s ``install_command``) import the dependencies of the Python
that runs asv: a ``.pth`` file in the environment's site-packages naming that Python's site-packages
(``ISOLATOR_ASV_SITE``, which the command line of ``benchmarks/README.md`` sets). A ``.pth`` line only adds
the folder to ``sys.path``: the ``.pth`` files inside it (an editable install of this project) are not run,
so the environment imports the commit's own wheel, installed after this.

    ISOLATOR_ASV_SITE=/path/to/site-packages python benchmarks/asv_shared_site.py
"""

from __future__ import annotations

import os
import sys
import sysconfig
from pathlib import Path


def main() -> None:
    shared = os.environ.get("ISOLATOR_ASV_SITE", "")
    if not shared or not Path(shared).is_dir():
        sys.exit("ISOLATOR_ASV_SITE: must name the site-packages folder of the Python that runs asv "
                 f"(got {shared!r}); see benchmarks/README.md")
    own = Path(sysconfig.get_paths()["purelib"])
    (own / "isolator_asv_shared.pth").write_text(shared + "\n")


if __name__ == "__main__":
    main()
