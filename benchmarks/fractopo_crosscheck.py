"""Cross-check rockmass's GeoPackage trace layers against fractopo itself: validation labels trace
by trace, node and branch counts, P21.

fractopo is not a rockmass dependency (it pulls geopandas and more), so this runs in a separate
environment that has it:

    python3 -m venv /tmp/fv && /tmp/fv/bin/pip install -q fractopo==0.9.2
    rockmass traces out/quickstart/extract/traces.geojson --gis gpkg --out /tmp/q_gis
    /tmp/fv/bin/python benchmarks/fractopo_crosscheck.py /tmp/q_gis/traces.gpkg SNAP

SNAP is the snap tolerance rockmass used (``validation.snap_tolerance`` in the traces stage's
summary.json). docs/fractures.md §9.1 quotes its output for the quickstart photo.
"""

import ast
import sys
import warnings
from collections import Counter

warnings.filterwarnings("ignore")
import geopandas as gpd  # noqa: E402
from fractopo import Network  # noqa: E402
from fractopo.tval.trace_validation import Validation  # noqa: E402


def main(path: str, snap: float) -> None:
    traces = gpd.read_file(path, layer="traces")
    area = gpd.read_file(path, layer="area")
    nodes = gpd.read_file(path, layer="nodes")
    branches = gpd.read_file(path, layer="branches")
    ours = [tuple(ast.literal_eval(v)) for v in traces["VALIDATION_ERRORS"]]  # fractopo's own text form
    checked = Validation(traces.drop(columns=["VALIDATION_ERRORS"]), area, name="x",
                         allow_fix=False, SNAP_THRESHOLD=snap).run_validation()
    theirs = [tuple(v) for v in checked[Validation.ERROR_COLUMN]]
    print("flagged: fractopo", sum(map(bool, theirs)), "rockmass", sum(map(bool, ours)),
          "of", len(theirs))
    print("labels: fractopo", dict(Counter(x for t in theirs for x in t)),
          " rockmass", dict(Counter(x for t in ours for x in t)))
    differ = [i for i, (o, t) in enumerate(zip(ours, theirs)) if set(o) != set(t)]
    print("traces whose labels differ:", len(differ), differ[:20])
    net = Network(traces, area, name="x", truncate_traces=True, circular_target_area=False,
                  determine_branches_nodes=True, snap_threshold=snap)
    print("nodes: fractopo", dict(Counter(net.node_types)),
          " rockmass", dict(Counter(nodes["Class"])))
    print("branches: fractopo", dict(Counter(net.branch_types)),
          " rockmass", dict(Counter(branches["Connection"])))
    print("P21: fractopo", net.parameters["Fracture Intensity P21"])


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]))
