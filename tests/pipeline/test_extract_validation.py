"""``rockmass extract`` flags its traces as fractopo's validation would (issue 19, item 4)."""

import json

from rockmass.cli import main
from rockmass.dfn import read_traces, validate_traces
from rockmass.dfn.trace_validation import errors_text
from rockmass.imaging import save_synthetic_face, synthetic_face


def test_extracted_traces_carry_their_validation_labels_and_the_summary_counts_them(tmp_path):
    face = synthetic_face("easy", seed=11, shape_px=(300, 450), m_per_px=0.02)
    photo = save_synthetic_face(face, tmp_path)["image"]
    out = tmp_path / "out"
    assert main(["extract", str(photo), "--m-per-px", "0.02", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())["statistics"]
    traces = read_traces(out / "traces.geojson")
    labels = traces.attributes["VALIDATION_ERRORS"].tolist()
    assert len(labels) == traces.n_traces == summary["Number of Traces"]["value"]
    assert sum(text != "()" for text in labels) == summary["validation"]["traces_flagged"]
    # the same traces checked again, with the summary's snap tolerance, give the same labels
    tau = summary["validation"]["snap_tolerance"]["value"]
    assert labels == errors_text(validate_traces(traces, snap_tolerance_m=tau).errors()).tolist()
