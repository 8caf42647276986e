"""The one colour scale of utilisation, defined once for every picture and page.

Utilisation (peak von Mises / the allowable, %) is coloured the same way in the report's PNGs
(the von Mises and the factor-of-safety pictures), the report's interactive 3-D view, the
sweep's maps and the explorer: the perceptually uniform ``viridis`` from 0 % (dark blue) to
100 % (yellow), magenta above 100 % (beyond the allowable), light grey where nothing was
computed.  Yellow therefore always means "at the allowable", never 44 % or 140 %.  Other
quantities (displacement) use a map that shares none of these colours.

The pages (JavaScript) get :data:`UTILISATION_STOPS`, the same map sampled at every 10 %, so
this module is all that names the map; a test checks the stops against matplotlib's.  Nothing
here imports matplotlib: a warm check writes its pages without it.
"""

from __future__ import annotations

__all__ = ["UTILISATION_CMAP", "UTILISATION_SCALE_PCT", "ABOVE_COLOUR", "NO_DATA_COLOUR", "UTILISATION_STOPS",
           "DISPLACEMENT_CMAP", "scale_json", "colormap"]

#: the one colour map of utilisation (matplotlib / pyvista name)
UTILISATION_CMAP = "viridis"
#: the one range it spans: 0 to 100 % of the allowable
UTILISATION_SCALE_PCT = (0.0, 100.0)
#: above 100 % of the allowable, and where no utilisation was computed (maps, explorer)
ABOVE_COLOUR, NO_DATA_COLOUR = "#ff00ff", "#c8c8c8"
#: :data:`UTILISATION_CMAP` at 0, 10, ..., 100 % as 0-255 RGB (the pages interpolate between them)
UTILISATION_STOPS = [[68, 1, 84], [72, 36, 117], [65, 68, 135], [53, 95, 141], [42, 120, 142], [33, 145, 140],
                     [34, 168, 132], [68, 191, 112], [122, 209, 81], [189, 223, 38], [253, 231, 37]]
#: displacement magnitude: a single-hue ramp, nothing like the utilisation colours
DISPLACEMENT_CMAP = "Blues"


def scale_json() -> dict:
    """The scale as the pages' JavaScript reads it."""
    return {"cmap": UTILISATION_CMAP, "range_pct": list(UTILISATION_SCALE_PCT), "stops": UTILISATION_STOPS,
            "above": ABOVE_COLOUR, "none": NO_DATA_COLOUR}


def colormap(name: str = UTILISATION_CMAP, above: str | None = ABOVE_COLOUR):
    """The matplotlib colour map ``name`` with ``above`` as its over colour; the displacement ramp
    starts at a light blue, not white (a part at rest stays visible on the white page)."""
    import matplotlib
    from matplotlib.colors import ListedColormap

    cm = matplotlib.colormaps[name]
    if name == DISPLACEMENT_CMAP:
        import numpy as np

        cm = ListedColormap(cm(np.linspace(0.25, 1.0, 256)), name=f"{name}_from_light")
    return cm.with_extremes(over=above) if above else cm
