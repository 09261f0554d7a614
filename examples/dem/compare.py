"""MPM against DEM + pore fluid (YADE's PFV FlowEngine), side by side: the oedometer.

Run:  yade-double -n -x examples/dem/compare.py oedometer [--quick] [--out DIR]
      (or /usr/bin/python3 -m yade_mpm.compare oedometer [--quick] [--out DIR])

Full: 1000 grains, 40 MPM cells over the height (a few minutes); --quick: 300 grains, 20 cells
(about 15 s). Writes DIR/report.md, DIR/report.json and DIR/oedometer.png (doc/dem-comparison.md).
"""
import sys

from yade_mpm import compare

sys.exit(compare.main(sys.argv[1:]))
