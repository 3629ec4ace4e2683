"""python -m sgim_nodes.sweep SWEEP.yaml: see driver.py."""

from sgim_nodes.sweep.driver import main

raise SystemExit(main())
