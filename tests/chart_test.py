"""scripts/chart-speed-accuracy.py's arithmetic and labels, without rendering: the summary's seconds
to reach a relMSE, each point's bars, the summary's columns, labels that overlap neither each other
nor the markers, and the document's tables written from the JSON. The label test needs matplotlib
(Debian: python3-matplotlib) and is skipped without it, as the script itself needs it to draw.

  python3 -m pytest -q tests/chart_test.py
"""
import importlib.util
import json
import math
import os

import pytest

SCRIPT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts",
                      "chart-speed-accuracy.py")
spec = importlib.util.spec_from_file_location("chart_speed_accuracy", SCRIPT)
chart = importlib.util.module_from_spec(spec)
spec.loader.exec_module(chart)


def curve(pairs):
    return [{"seconds": s, "relmse": e, "setting": f"{s:g} s"} for s, e in pairs]


def test_time_to_reach_interpolates_on_log_log_axes():
    # relMSE = 0.02 / seconds, a straight line on log-log axes: the time to any relMSE between two
    # points is exactly 0.02 / relMSE, wherever the points lie on the line.
    points = curve([(0.5, 0.04), (3.0, 0.02 / 3.0), (40.0, 0.0005)])
    for target in (0.01, 0.001, 0.003):
        seconds, how = chart.time_to_reach(points, target, unbiased=False)
        assert how == ""
        assert seconds == pytest.approx(0.02 / target, rel=1e-12)
    # The order the points come in does not matter.
    assert chart.time_to_reach(points[::-1], 0.001, False)[0] == pytest.approx(20.0, rel=1e-12)


def test_time_to_reach_says_how_it_was_found():
    points = curve([(1.0, 0.005), (4.0, 0.00125)])
    # Already below at its fastest point: at most that long.
    assert chart.time_to_reach(points, 0.01, False) == (1.0, "at most")
    # An unbiased curve ending above the target: its relMSE falls as 1 / time from its last point.
    seconds, how = chart.time_to_reach(points, 0.0001, True)
    assert how == "extrapolated"
    assert seconds == pytest.approx(4.0 * 0.00125 / 0.0001, rel=1e-12)
    # A biased method that flattens above the target never gets there.
    assert chart.time_to_reach(curve([(1.0, 0.01), (4.0, 0.008), (16.0, 0.0079)]), 0.001, False) is None
    assert chart.time_to_reach([], 0.001, True) is None


def test_bars_span_the_seeds_range():
    points = [{"seconds": 2.0, "seconds_range": [1.5, 3.0], "relmse": 0.01, "relmse_range": [0.008, 0.011]},
              {"seconds": 5.0, "relmse": 0.002}]
    assert chart.spread(points, "seconds") == [[0.5, 0.0], [1.0, 0.0]]
    lower, upper = chart.spread(points, "relmse")
    assert lower == pytest.approx([0.002, 0.0])
    assert upper == pytest.approx([0.001, 0.0])


def test_summary_columns_gather_a_methods_knobs():
    assert chart.family("particles (bounces)") == "particles"
    assert chart.family("envpbgi (points)") == "envpbgi"
    assert chart.family("pt (depth 2, independent)") == "pt (independent)"
    assert chart.family("pt (depth 2)") == "pt"
    assert chart.family("pt (target error)") == "pt (target error)"


def label_boxes(fig, ax):
    """The window boxes of the axes' annotations, and of their points' markers (6 x 6 pixels)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    labels, markers = [], []
    for a in ax.texts:
        b = a.get_window_extent(renderer)
        labels.append((b.x0, b.y0, b.x1, b.y1))
        mx, my = ax.transData.transform(a.xy)
        markers.append((mx - 3, my - 3, mx + 3, my + 3))
    return labels, markers


def overlapping(a, b):
    return min(a[2], b[2]) > max(a[0], b[0]) and min(a[3], b[3]) > max(a[1], b[1])


@pytest.mark.parametrize("offsets", ["the script's", "one"])
def test_labels_overlap_neither_each_other_nor_markers(offsets, monkeypatch):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if offsets == "one":
        # Negative control: every label at the same offset from its point.
        monkeypatch.setattr(chart, "LABEL_OFFSETS", [(5, 3)])
    # Three curves of five settings each, crowded as the charts' are where methods meet.
    fig, ax = plt.subplots(figsize=(9.5, 5.5), dpi=110)
    labels = []
    for k, scale in enumerate((0.02, 0.022, 0.024)):
        points = [(s * (1 + 0.05 * k), scale / s) for s in (0.5, 1.0, 2.0, 4.0, 8.0)]
        ax.plot(*zip(*points), marker="o", markersize=3)
        labels += [(x, y, f"{16 * 2 ** i} gather rays") for i, (x, y) in enumerate(points)]
    ax.set_xscale("log")
    ax.set_yscale("log")
    fig.tight_layout()
    chart.place_labels(fig, ax, labels)
    boxes, markers = label_boxes(fig, ax)
    plt.close(fig)
    assert len(boxes) == len(labels)
    clashes = [(i, j) for i in range(len(boxes)) for j in range(i + 1, len(boxes)) if overlapping(boxes[i], boxes[j])]
    clashes += [(i, "marker", j) for i in range(len(boxes)) for j in range(len(markers))
                if overlapping(boxes[i], markers[j])]
    if offsets == "one":
        assert clashes
    else:
        assert not clashes


def test_counts_are_labelled_with_their_fraction_of_a_thousand():
    assert [label for label, _ in chart.photons(["--photons"], "photons", 12500, 1040000)] == ["12.5k photons",
                                                                                                "1040k photons"]
    assert chart.particle_knobs(37500, (37500,))["particles (area particles)"][0][0] == "37.5k particles"


def test_settings_share_their_unit_in_one_cell():
    assert chart.compact_settings(["4 spp", "16 spp", "64 spp"]) == "4 / 16 / 64 spp"
    assert chart.compact_settings(["8x8 buffers", "16x16 buffers"]) == "8x8 / 16x16 buffers"
    assert chart.compact_settings(["n_b 1", "n_b 2", "n_b 4"]) == "n_b 1 / 2 / 4"
    assert chart.compact_settings(["8x8, 4x4", "16x16, 8x8"]) == "8x8, 4x4 / 16x16, 8x8"
    assert chart.compact_settings(["E 0.01", "E 0.003"]) == "E 0.01 / 0.003"
    assert chart.compact_settings(["1k photons"]) == "1k photons"


def test_tables_are_written_between_their_markers_from_the_json():
    everything = {"cornell-box": {"pt": [{"setting": "4 spp", "seconds": 0.0612, "relmse": 0.16675},
                                         {"setting": "16 spp", "seconds": 0.18, "relmse": 0.029851}],
                                  "purcell": [{"setting": "16k photons", "seconds": 0.24, "relmse": 0.0140}]}}
    _, _, table = chart.times_to_targets(everything)
    stale = "| curve | settings | seconds | relMSE |\n| old | row | 1 | 2 |"
    doc = ("# Title\n\n" + chart.block("cornell-box") + "\n" + stale + "\n" + chart.END_BLOCK + "\n\nprose\n\n"
           + chart.block("summary") + "\n" + chart.END_BLOCK + "\n")
    written = chart.doc_with_tables(doc, everything, table)
    assert "| old | row |" not in written
    assert "| pt | 4 / 16 spp | 0.0612 / 0.18 | 0.17 / 0.03 |" in written
    assert "| purcell | 16k photons | 0.24 | 0.014 |" in written
    # purcell reaches 0.01 nowhere (biased), the path tracer's curve is extended as 1 / time.
    assert "| seconds to relMSE 0.01, 0.001 | pt | purcell |" in written
    assert "| cornell-box | ~0.54, ~5.4 | never, never |" in written
    assert written.endswith("prose\n\n" + chart.block("summary") + "\n" + "\n".join(chart.summary_table(table))
                            + "\n" + chart.END_BLOCK + "\n")
    # Written again, nothing changes; a table of a scene the JSON lacks is refused.
    assert chart.doc_with_tables(written, everything, table) == written
    with pytest.raises(SystemExit):
        chart.doc_with_tables(chart.block("maze") + "\n" + chart.END_BLOCK, everything, table)


def test_the_documents_tables_are_those_of_the_json():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with open(os.path.join(root, "docs", "charts", "speed-accuracy.json")) as f:
        everything = json.load(f)
    with open(os.path.join(root, "docs", "speed-accuracy.md")) as f:
        doc = f.read()
    # Every scene charted, and the summary, has its table in the document, as the JSON gives it.
    for key in list(everything) + ["summary"]:
        assert chart.block(key) in doc, key
    assert chart.doc_with_tables(doc, everything, chart.times_to_targets(everything)[2]) == doc
