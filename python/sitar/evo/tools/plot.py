"""evo.tools.plot: trajectories and error arrays in matplotlib axes (matplotlib is an
optional dependency: ``pip install matplotlib``).

The figures hold what evo's hold (the same line data, axes, labels, legend, colour bar
ticks) with evo's settings (``sitar.evo.tools.settings.SETTINGS``, evo's defaults: colour
map ``jet``, legend shown, equal aspect for trajectories, Euler angles ``sxyz``; statistics
in the colours of seaborn's ``deep6`` palette). Unlike evo, importing this module changes no
matplotlib settings (evo sets its backend, a seaborn style and rcParams from
``~/.evo/settings.json``), and that file is not read.
"""

import itertools
import typing
from enum import Enum, unique

import numpy as np

try:
    import matplotlib as mpl
    import matplotlib.pyplot as plt
    from matplotlib import cm
    from matplotlib.collections import LineCollection
    from matplotlib.ticker import FuncFormatter
    from mpl_toolkits.mplot3d import Axes3D, art3d
except ImportError as _error:  # pragma: no cover - exercised without matplotlib only
    raise ImportError(
        "sitar.evo.tools.plot needs matplotlib (pip install matplotlib)"
    ) from _error

from sitar.evo import EvoException
from sitar.evo._missing import missing
from sitar.evo.core import trajectory
from sitar.evo.core.units import LENGTH_UNITS, METER_SCALE_FACTORS, Unit
from sitar.evo.tools.settings import SETTINGS

ListOrArray = typing.Union[typing.Sequence[float], np.ndarray]

# seaborn's "deep6" palette, evo's default for statistics lines.
_DEEP6 = [
    (0.298039, 0.447059, 0.690196),
    (0.333333, 0.658824, 0.407843),
    (0.768627, 0.305882, 0.321569),
    (0.505882, 0.447059, 0.701961),
    (0.8, 0.72549, 0.454902),
    (0.392157, 0.709804, 0.803922),
]


class PlotException(EvoException):
    pass


@unique
class PlotMode(Enum):
    xy = "xy"
    xz = "xz"
    yx = "yx"
    yz = "yz"
    zx = "zx"
    zy = "zy"
    xyz = "xyz"


def color_cycle() -> list:
    """The colours of statistics lines (seaborn's deep6 palette, evo's default)."""
    return list(_DEEP6)


def set_aspect_equal(ax) -> None:
    """Equal scale on every axis (3D: a cube around the data's limits)."""
    if not isinstance(ax, Axes3D):
        ax.set_aspect("equal")
        return
    limits = [ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()]
    centres = [np.mean(lim) for lim in limits]
    radius = max(abs(v - c) for lim, c in zip(limits, centres) for v in lim)
    ax.set_xlim3d([centres[0] - radius, centres[0] + radius])
    ax.set_ylim3d([centres[1] - radius, centres[1] + radius])
    ax.set_zlim3d([centres[2] - radius, centres[2] + radius])


def _length_formatter(length_unit: Unit) -> FuncFormatter:
    return FuncFormatter(lambda x, _: f"{x / METER_SCALE_FACTORS[length_unit]:g}")


def prepare_axis(fig, plot_mode: PlotMode = PlotMode.xy, subplot_arg: int = 111,
                 length_unit: Unit = Unit.meters):
    """A subplot of ``fig`` for ``plot_mode`` (3D for xyz) with evo's axis labels."""
    if length_unit not in LENGTH_UNITS:
        raise PlotException(f"{length_unit} is not a length unit")
    if plot_mode == PlotMode.xyz:
        ax = fig.add_subplot(subplot_arg, projection="3d")
        ax.set_box_aspect(None, zoom=SETTINGS.plot_3d_zoom)
    else:
        ax = fig.add_subplot(subplot_arg)
    unit = length_unit.value
    first = {"x": "x", "y": "y", "z": "z"}[plot_mode.value[0]]
    second = "y" if plot_mode == PlotMode.xyz else plot_mode.value[1]
    ax.set_xlabel(f"${first}$ ({unit})")
    ax.set_ylabel(f"${second}$ ({unit})")
    if plot_mode == PlotMode.xyz:
        ax.set_zlabel(f"$z$ ({unit})")
    if SETTINGS.plot_invert_xaxis:
        plt.gca().invert_xaxis()
    if SETTINGS.plot_invert_yaxis:
        plt.gca().invert_yaxis()
    if not SETTINGS.plot_show_axis:
        ax.set_axis_off()
    if length_unit is not Unit.meters:
        formatter = _length_formatter(length_unit)
        ax.xaxis.set_major_formatter(formatter)
        ax.yaxis.set_major_formatter(formatter)
        if plot_mode == PlotMode.xyz:
            ax.zaxis.set_major_formatter(formatter)
    return ax


def plot_mode_to_idx(plot_mode: PlotMode) -> typing.Tuple[int, int, typing.Optional[int]]:
    """The column indices (x, y, z or None) a plot mode draws."""
    axis = {"x": 0, "y": 1, "z": 2}
    if plot_mode == PlotMode.xyz:
        return 0, 1, 2
    return axis[plot_mode.value[0]], axis[plot_mode.value[1]], None


def add_start_end_markers(ax, plot_mode: PlotMode, traj: trajectory.PosePath3D,
                          start_symbol: str = "o", start_color="black", end_symbol: str = "x",
                          end_color="black", alpha: float = 1.0,
                          traj_name: typing.Optional[str] = None) -> None:
    """A marker at the first and one at the last position."""
    if traj.num_poses == 0:
        return
    ids = [i for i in plot_mode_to_idx(plot_mode) if i is not None]
    start, end = traj.positions_xyz[0][ids], traj.positions_xyz[-1][ids]
    ax.scatter(*start, marker=start_symbol, color=start_color, alpha=alpha,
               label=f"Start of {traj_name}" if traj_name else None)
    ax.scatter(*end, marker=end_symbol, color=end_color, alpha=alpha,
               label=f"End of {traj_name}" if traj_name else None)


def traj(ax, plot_mode: PlotMode, traj: trajectory.PosePath3D, style: str = "-",
         color="black", label: str = "", alpha: float = 1.0,
         plot_start_end_markers: bool = False) -> None:
    """The path's positions as one line in the plane (or space) of ``plot_mode``."""
    ids = [i for i in plot_mode_to_idx(plot_mode) if i is not None]
    columns = [traj.positions_xyz[:, i] for i in ids]
    ax.plot(*columns, style, color=color, label=label, alpha=alpha)
    if SETTINGS.plot_xyz_realistic:
        set_aspect_equal(ax)
    if label and SETTINGS.plot_show_legend:
        ax.legend(frameon=True)
    if plot_start_end_markers:
        add_start_end_markers(ax, plot_mode, traj, start_color=color, end_color=color,
                              alpha=alpha)


def colored_line_collection(xyz: np.ndarray, colors, plot_mode: PlotMode = PlotMode.xy,
                            linestyles: str = "solid", step: int = 1, alpha: float = 1.0):
    """One segment per consecutive pair of positions (every ``step``), coloured in turn."""
    if step > 1 and len(xyz) / step != len(colors):
        raise PlotException(
            "color values don't have correct length: %d vs. %d" % (len(xyz) / step, len(colors))
        )
    ids = [i for i in plot_mode_to_idx(plot_mode) if i is not None]
    starts = xyz[:-1:step][:, ids]
    ends = xyz[1::step][:, ids]
    n = min(len(starts), len(ends))
    segments = np.stack([starts[:n], ends[:n]], axis=1)
    if plot_mode == PlotMode.xyz:
        return art3d.Line3DCollection(segments, colors=colors, alpha=alpha, linestyles=linestyles)
    return LineCollection(segments, colors=colors, alpha=alpha, linestyle=linestyles)


def traj_colormap(ax, traj: trajectory.PosePath3D, array: ListOrArray, plot_mode: PlotMode,
                  min_map: float, max_map: float, title: str = "", fig=None,
                  plot_start_end_markers: bool = False) -> None:
    """The path coloured by ``array`` (one value per pose, ``jet`` from ``min_map`` to
    ``max_map``) with a colour bar of three ticks."""
    norm = mpl.colors.Normalize(vmin=min_map, vmax=max_map, clip=True)
    mapper = cm.ScalarMappable(norm=norm, cmap=SETTINGS.plot_trajectory_cmap)
    mapper.set_array(array)
    colors = [mapper.to_rgba(a) for a in array]
    ax.add_collection(colored_line_collection(traj.positions_xyz, colors, plot_mode))
    ax.autoscale_view(True, True, True)
    if plot_mode == PlotMode.xyz and isinstance(ax, Axes3D):
        low, high = np.amin(traj.positions_xyz[:, 2]), np.amax(traj.positions_xyz[:, 2])
        if low != high:
            ax.set_zlim(low, high)
    if SETTINGS.plot_xyz_realistic:
        set_aspect_equal(ax)
    if fig is None:
        fig = plt.gcf()
    middle = max_map - (max_map - min_map) / 2
    bar = fig.colorbar(mapper, ticks=[min_map, middle, max_map], ax=ax)
    bar.ax.set_yticklabels([f"{min_map:0.3f}", f"{middle:0.3f}", f"{max_map:0.3f}"])
    if title:
        ax.set_title(title)
    if SETTINGS.plot_show_legend and ax.get_legend_handles_labels()[1]:
        ax.legend(frameon=True)
    if plot_start_end_markers:
        add_start_end_markers(ax, plot_mode, traj, start_color=colors[0], end_color=colors[-1])


def _time_axis(traj: trajectory.PosePath3D, count: int, start_timestamp):
    if isinstance(traj, trajectory.PoseTrajectory3D):
        x = traj.timestamps - start_timestamp if start_timestamp else traj.timestamps
        return x, "$t$ (s)"
    return np.arange(0.0, count, dtype=float), "index"


def _three(axarr) -> None:
    if len(axarr) != 3:
        raise PlotException("expected an axis array with 3 subplots - got " + str(len(axarr)))


def traj_xyz(axarr, traj: trajectory.PosePath3D, style: str = "-", color="black",
             label: str = "", alpha: float = 1.0, start_timestamp: typing.Optional[float] = None,
             length_unit: Unit = Unit.meters) -> None:
    """x, y and z over time (or index) in three axes."""
    _three(axarr)
    if length_unit not in LENGTH_UNITS:
        raise PlotException(f"{length_unit} is not a length unit")
    x, xlabel = _time_axis(traj, len(traj.positions_xyz), start_timestamp)
    for i, name in enumerate("xyz"):
        if length_unit is not Unit.meters:
            axarr[i].yaxis.set_major_formatter(_length_formatter(length_unit))
        axarr[i].plot(x, traj.positions_xyz[:, i], style, color=color, label=label, alpha=alpha)
        axarr[i].set_ylabel(f"${name}$ ({length_unit.value})")
    axarr[2].set_xlabel(xlabel)
    if label and SETTINGS.plot_show_legend:
        axarr[0].legend(frameon=True)


def traj_rpy(axarr, traj: trajectory.PosePath3D, style: str = "-", color="black",
             label: str = "", alpha: float = 1.0,
             start_timestamp: typing.Optional[float] = None) -> None:
    """Roll, pitch and yaw (degrees, Euler sxyz) over time (or index) in three axes."""
    _three(axarr)
    angles = traj.get_orientations_euler(SETTINGS.euler_angle_sequence)
    x, xlabel = _time_axis(traj, len(angles), start_timestamp)
    for i, name in enumerate(("roll", "pitch", "yaw")):
        axarr[i].plot(x, np.rad2deg(angles[:, i]), style, color=color, label=label, alpha=alpha)
        axarr[i].set_ylabel(f"${name}$ (deg)")
    axarr[2].set_xlabel(xlabel)
    if label and SETTINGS.plot_show_legend:
        axarr[0].legend(frameon=True)


def error_array(ax, err_array: ListOrArray, x_array: typing.Optional[ListOrArray] = None,
                statistics: typing.Optional[typing.Dict[str, float]] = None,
                threshold: typing.Optional[float] = None, cumulative: bool = False,
                color="grey", name: str = "error", title: str = "", xlabel: str = "index",
                ylabel: typing.Optional[str] = None, subplot_arg: int = 111,
                linestyle: str = "-", marker: typing.Optional[str] = None) -> None:
    """The error values (or their running sum), a line per statistic (``std`` as a band of
    ±std/2 around the mean), a dashed ``threshold``; labels, title and legend on the
    current axes, as evo."""
    values = np.cumsum(err_array) if cumulative else err_array
    data = (values,) if x_array is None else (x_array, values)
    ax.plot(*data, linestyle=linestyle, marker=marker, color=color, label=name)
    palette = itertools.cycle(color_cycle())
    if statistics is not None:
        for stat_name, value in statistics.items():
            stat_color = next(palette)
            if stat_name == "std" and "mean" in statistics:
                mean, std = statistics["mean"], statistics["std"]
                ax.axhspan(mean - std / 2, mean + std / 2, color=stat_color, alpha=0.5,
                           label=stat_name)
            else:
                ax.axhline(y=value, color=stat_color, linewidth=2.0, label=stat_name)
    if threshold is not None:
        ax.axhline(y=threshold, color="red", linestyle="dashed", linewidth=2.0,
                   label="threshold")
    plt.ylabel(ylabel if ylabel else name)
    plt.xlabel(xlabel)
    plt.title(title)
    if SETTINGS.plot_show_legend:
        plt.legend(frameon=True)


__getattr__ = missing(
    "evo.tools.plot",
    {
        name: "sitar ape|rpe|traj --plot / --save_plot (the sitar command's figures)"
        for name in (
            "PlotCollection",
            "trajectories",
            "speeds",
            "ros_map",
            "map_tile",
            "draw_coordinate_axes",
            "draw_correspondence_edges",
            "apply_settings",
            "Viewport",
        )
    },
)
