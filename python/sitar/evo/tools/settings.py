"""evo.tools.settings' ``SETTINGS``: evo's default settings, read by ``sitar.evo.tools.plot``
(legend, equal aspect, colour map, Euler sequence, 3D zoom, axis inversion and visibility).
Scripts may set them (``SETTINGS.plot_show_legend = False``) as in evo; evo's settings
file (``~/.evo/settings.json``) is not read."""

from sitar.evo import EvoException


class SettingsException(EvoException):
    pass


class SettingsContainer(dict):
    """A dict whose keys are attributes too; unknown names are a SettingsException."""

    def __getattr__(self, name):
        if name not in self:
            raise SettingsException("unknown settings parameter: " + str(name))
        return self[name]

    def __setattr__(self, name, value):
        self[name] = value


# evo 1.38.1's defaults of the settings its plots read.
DEFAULT_SETTINGS_DICT = {
    "euler_angle_sequence": "sxyz",
    "plot_3d_zoom": 0.9,
    "plot_backend": "Agg",
    "plot_figsize": [10, 10],
    "plot_fontfamily": "sans-serif",
    "plot_fontscale": 1.0,
    "plot_invert_xaxis": False,
    "plot_invert_yaxis": False,
    "plot_legend_loc": "best",
    "plot_linewidth": 1.5,
    "plot_mode_default": "xyz",
    "plot_reference_alpha": 0.5,
    "plot_reference_color": "#444444",
    "plot_reference_linestyle": "--",
    "plot_seaborn_palette": "deep6",
    "plot_show_axis": True,
    "plot_show_legend": True,
    "plot_split": False,
    "plot_start_end_markers": False,
    "plot_statistics": ["rmse", "median", "mean", "std", "min", "max"],
    "plot_trajectory_alpha": 0.75,
    "plot_trajectory_cmap": "jet",
    "plot_trajectory_length_unit": "m",
    "plot_trajectory_linestyle": "-",
    "plot_usetex": False,
    "plot_xyz_realistic": True,
}

SETTINGS = SettingsContainer(DEFAULT_SETTINGS_DICT)
