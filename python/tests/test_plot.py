"""``sitar.evo.tools.plot`` against evo's: the same artists with the same data in the same
axes (lines, segments, markers, spans), the same labels, titles, legends and colour bars."""

import copy

import numpy as np
import pytest

mpl = pytest.importorskip("matplotlib", reason="SKIPPED: no matplotlib")
mpl.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

evo_plot = pytest.importorskip("evo.tools.plot", reason="SKIPPED: evo is not installed")
from evo.core import metrics as evo_metrics  # noqa: E402
from evo.tools import file_interface as evo_fi  # noqa: E402

from sitar.evo.core import metrics  # noqa: E402
from sitar.evo.tools import file_interface, plot  # noqa: E402


def content(fig):
    """Everything drawn, axis by axis: texts, line data, collections' segments, legend."""
    out = []
    for ax in fig.axes:
        item = {
            "labels": (ax.get_xlabel(), ax.get_ylabel(), ax.get_title(),
                       getattr(ax, "get_zlabel", lambda: None)()),
            "lines": [(l.get_label(), np.asarray(l.get_xdata(), float), np.asarray(l.get_ydata(), float),
                       mpl.colors.to_rgba(l.get_color()), l.get_linestyle())
                      for l in ax.get_lines()],
            "collections": [np.asarray(c.get_segments() if hasattr(c, "get_segments") else
                                       c.get_offsets(), dtype=float) for c in ax.collections],
            "patches": [np.asarray(p.get_xy(), float) for p in ax.patches if hasattr(p, "get_xy")],
            "legend": [t.get_text() for t in ax.get_legend().get_texts()] if ax.get_legend() else None,
            "yticklabels": [t.get_text() for t in ax.get_yticklabels()] if ax.get_label() == "<colorbar>" else None,
        }
        if hasattr(ax, "get_zlim"):
            item["segments3d"] = [np.asarray(c._segments3d, float) for c in ax.collections
                                  if hasattr(c, "_segments3d")]
        out.append(item)
    return out


def assert_same(ours, theirs):
    assert len(ours) == len(theirs), "the same number of axes"
    for a, b in zip(ours, theirs):
        assert a["labels"] == b["labels"]
        assert a["legend"] == b["legend"]
        assert a["yticklabels"] == b["yticklabels"]
        assert len(a["lines"]) == len(b["lines"])
        for la, lb in zip(a["lines"], b["lines"]):
            assert la[0] == lb[0] and la[4] == lb[4]
            np.testing.assert_allclose(la[1], lb[1], atol=1e-9)
            np.testing.assert_allclose(la[2], lb[2], atol=1e-9)
            np.testing.assert_allclose(la[3], lb[3], atol=1e-6)
        assert len(a["collections"]) == len(b["collections"])
        for ca, cb in zip(a["collections"], b["collections"]):
            np.testing.assert_allclose(ca, cb, atol=1e-9)
        for pa, pb in zip(a["patches"], b["patches"]):
            np.testing.assert_allclose(pa, pb, atol=1e-9)
        for sa, sb in zip(a.get("segments3d", []), b.get("segments3d", [])):
            np.testing.assert_allclose(sa, sb, atol=1e-9)


@pytest.fixture(scope="module")
def data(synthetic):
    ref, est = synthetic
    ours = (file_interface.read_tum_trajectory_file(str(ref)),
            file_interface.read_tum_trajectory_file(str(est)))
    theirs = (evo_fi.read_tum_trajectory_file(str(ref)), evo_fi.read_tum_trajectory_file(str(est)))
    ours[1].align(ours[0])
    theirs[1].align(theirs[0])
    ape_ours, ape_theirs = metrics.APE(), evo_metrics.APE()
    ape_ours.process_data(ours)
    ape_theirs.process_data(theirs)
    return ours, theirs, ape_ours, ape_theirs


def draw(module, trajs, ape, mode_name, what):
    fig = plt.figure()
    mode = module.PlotMode[mode_name]
    if what == "traj":
        ax = module.prepare_axis(fig, mode)
        module.traj(ax, mode, trajs[0], "--", "gray", "reference")
        module.traj(ax, mode, trajs[1], "-", "blue", "estimate", plot_start_end_markers=True)
    elif what == "colormap":
        ax = module.prepare_axis(fig, mode)
        module.traj_colormap(ax, trajs[1], ape.error, mode, min_map=float(ape.error.min()),
                             max_map=float(ape.error.max()), title="APE mapped onto trajectory",
                             fig=fig)
    elif what == "xyz":
        plt.close(fig)
        fig, axarr = plt.subplots(3)
        module.traj_xyz(axarr, trajs[0], "--", "gray", "reference")
        module.traj_xyz(axarr, trajs[1], "-", "blue", "estimate", start_timestamp=trajs[0].timestamps[0])
    elif what == "rpy":
        plt.close(fig)
        fig, axarr = plt.subplots(3)
        module.traj_rpy(axarr, trajs[0], "--", "gray", "reference")
        module.traj_rpy(axarr, trajs[1], "-", "blue", "estimate")
    elif what == "error":
        ax = fig.add_subplot(111)
        module.error_array(ax, ape.error, x_array=trajs[1].timestamps - trajs[1].timestamps[0],
                           statistics={k: v for k, v in ape.get_all_statistics().items() if k != "sse"},
                           threshold=0.01, name="APE", title=str(ape), xlabel="$t$ (s)")
    out = content(fig)
    plt.close(fig)
    return out


@pytest.mark.parametrize("what, mode", [("traj", "xy"), ("traj", "xz"), ("traj", "zy"),
                                        ("traj", "xyz"), ("colormap", "xy"), ("colormap", "xyz"),
                                        ("xyz", "xy"), ("rpy", "xy"), ("error", "xy")])
def test_figures_hold_what_evo_s_hold(data, what, mode):
    ours, theirs, ape_ours, ape_theirs = data
    assert_same(draw(plot, ours, ape_ours, mode, what), draw(evo_plot, theirs, ape_theirs, mode, what))


def test_plot_errors_and_what_is_not_mirrored(data):
    fig, axarr = plt.subplots(2)
    with pytest.raises(plot.PlotException, match="3 subplots"):
        plot.traj_xyz(axarr, data[0][0])
    with pytest.raises(plot.PlotException, match="not a length unit"):
        plot.prepare_axis(fig, plot.PlotMode.xy, length_unit=plot.Unit.degrees)
    plt.close(fig)
    with pytest.raises(NotImplementedError, match="evo.tools.plot.PlotCollection"):
        plot.PlotCollection
