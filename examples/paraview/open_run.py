"""Open an hvi run in ParaView: the body warped by its displacement and coloured by its active
scalar (von Mises unless the scene's output.active_scalar names another field),
the contact boundary Gamma3 coloured by its normal displacement u_nu, at the run's times, and
beside them u_nu along Gamma3 at the shown time (Plot Over Line on contact.pvd).

    pvpython examples/paraview/open_run.py RUN_DIR            # renders RUN_DIR/paraview.png
    paraview --script=examples/paraview/open_run.py            # (RUN_DIR from HVI_RUN, default .)

With Debian's ParaView and no display, run pvpython under a virtual one:
`xvfb-run -a pvpython examples/paraview/open_run.py RUN_DIR` (docs/method.md §12.1).

RUN_DIR is an output directory of `hvi solve` (solution.pvd, contact.pvd). The arrays are
described in docs/method.md §12; the warp is the displacement times SCALE (default 1, set
HVI_WARP_SCALE to magnify a small-strain run). HVI_TIME picks the time shown (default: the
last); the nearest output time is shown.
"""

import os
import sys

from paraview.simple import (  # noqa: F401  (pvpython provides paraview.simple)
    AssignViewToLayout,
    ColorBy,
    CreateLayout,
    CreateView,
    GetActiveViewOrCreate,
    GetAnimationScene,
    GetColorTransferFunction,
    GetScalarBar,
    PlotData,
    PlotOverLine,
    PVDReader,
    Render,
    ResetCamera,
    SaveScreenshot,
    Show,
    WarpByVector,
)


def gamma3_line(bounds, flat):
    """The end points of a line along the contact dataset: through the middle of its bounds,
    along the coordinate of largest extent (a straight Gamma3 in 2D is this line; a flat Gamma3
    in 3D is cut through its middle). None for a single point."""
    extent = [bounds[2 * d + 1] - bounds[2 * d] for d in range(3)]
    axis = max(range(3), key=lambda d: extent[d])
    if extent[axis] <= 0.0:
        return None
    if flat and min(extent[0], extent[1]) > 1e-9 * extent[axis]:
        # a 2D Gamma3 that is not parallel to an axis: its diagonal (straight if it is a segment)
        return [bounds[0], bounds[2], 0.0], [bounds[1], bounds[3], 0.0]
    mid = [(bounds[2 * d] + bounds[2 * d + 1]) / 2.0 for d in range(3)]
    p1, p2 = list(mid), list(mid)
    p1[axis], p2[axis] = bounds[2 * axis], bounds[2 * axis + 1]
    return p1, p2


def active_scalar(run_dir):
    """The body's active point scalars (the scene's output.active_scalar, von_mises by default),
    as the last frame of solution.pvd marks them; von_mises if it marks none."""
    import re
    import xml.etree.ElementTree as ET

    frames = list(ET.parse(os.path.join(run_dir, "solution.pvd")).getroot().iter("DataSet"))
    if frames:
        with open(os.path.join(run_dir, frames[-1].get("file")), "rb") as f:
            head = f.read(8192).decode("latin-1")
        found = re.search(r'<PointData[^>]*\bScalars="([^"]+)"', head)
        if found:
            return found.group(1)
    return "von_mises"


def open_run(run_dir, scale=1.0, time=None, chart=True):
    """Loads solution.pvd (and contact.pvd if present) at `time` (default: the last output
    time); returns a dict with the readers, the render view and (with `chart`, when the run has
    a contact dataset) the line chart of u_nu along Gamma3 and its Plot Over Line filter."""
    layout = CreateLayout("hvi run") if chart else None
    view = CreateView("RenderView") if chart else GetActiveViewOrCreate("RenderView")
    if layout is not None:
        AssignViewToLayout(view=view, layout=layout, hint=0)
    view.OrientationAxesVisibility = 1
    body = PVDReader(FileName=os.path.join(run_dir, "solution.pvd"))
    times = list(body.TimestepValues)
    if time is None:
        shown_time = times[-1] if times else 0.0
    else:
        shown_time = min(times, key=lambda t: abs(t - time)) if times else 0.0
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = shown_time
    body.UpdatePipeline(shown_time)
    flat = _flat(body)
    warped = WarpByVector(Input=body)
    warped.Vectors = ["POINTS", "displacement"]
    warped.ScaleFactor = scale
    shown = Show(warped, view)
    scalar = active_scalar(run_dir)
    ColorBy(shown, ("POINTS", scalar))
    shown.RescaleTransferFunctionToDataRange(False, True)
    titles = {"von_mises": "von Mises stress", "displacement": "|u|", "stress": "|stress|"}
    _bar(view, scalar, titles.get(scalar, scalar), [0.6, 0.72])
    out = {"body": body, "view": view, "layout": layout, "time": shown_time, "times": times, "scalar": scalar}
    contact_pvd = os.path.join(run_dir, "contact.pvd")
    if os.path.exists(contact_pvd):
        contact = PVDReader(FileName=contact_pvd)
        # the contact dataset carries the displacement of its nodes: warped like the body
        cwarped = WarpByVector(Input=contact)
        cwarped.Vectors = ["POINTS", "displacement"]
        cwarped.ScaleFactor = scale
        if not flat:
            # a face drawn on the body's own face flickers (z-fighting): lift it off the body by
            # 0.2 % of the body's size along its outward normal (a display offset only)
            b = body.GetDataInformation().GetBounds()
            size = max(b[1] - b[0], b[3] - b[2], b[5] - b[4])
            cwarped = WarpByVector(Input=cwarped)
            cwarped.Vectors = ["POINTS", "normal"]
            cwarped.ScaleFactor = 2e-3 * size
        cshown = Show(cwarped, view)
        ColorBy(cshown, ("POINTS", "u_nu"))
        cshown.LineWidth = 5.0
        # the colour range of u_nu at the shown time (the first frame's is all zeros)
        cshown.RescaleTransferFunctionToDataRange(False, True)
        _bar(view, "u_nu", "u_nu on Gamma3", [0.14, 0.72])
        out["contact"] = contact
        if chart:
            contact.UpdatePipeline(shown_time)
            ends = gamma3_line(contact.GetDataInformation().GetBounds(), flat)
            chart_view = CreateView("XYChartView")
            chart_view.ChartTitle = "u_nu along Gamma3, t = %g" % shown_time
            chart_view.LeftAxisTitle = "u_nu"
            chart_view.BottomAxisTitle = "distance along Gamma3 (Plot Over Line)"
            for font in ("ChartTitleFontSize", "LeftAxisTitleFontSize", "BottomAxisTitleFontSize"):
                setattr(chart_view, font, 13)
            for font in ("LeftAxisLabelFontSize", "BottomAxisLabelFontSize", "LegendFontSize"):
                setattr(chart_view, font, 12)
            AssignViewToLayout(view=chart_view, layout=layout, hint=2)
            layout.SetSplitFraction(0, 0.58)
            if ends is not None:
                line = PlotOverLine(Input=contact)
                line.Point1, line.Point2 = ends
                line.Resolution = 400
                series = Show(line, chart_view)
                series.XArrayName = "arc_length"
                out["line"] = line
            else:
                line = PlotData(Input=contact)
                series = Show(line, chart_view)
            series.SeriesVisibility = ["u_nu"]
            out["chart"] = chart_view
    view.InteractionMode = "2D" if flat else "3D"
    if not flat:
        # y up as in the 2D pictures, seen from the front (+z), slightly from below Gamma3 (y = 0)
        view.CameraFocalPoint = [0.0, 0.0, 0.0]
        view.CameraPosition = [0.8, -1.6, 1.9]
        view.CameraViewUp = [0.0, 1.0, 0.0]
    ResetCamera(view)
    Render(view)
    return out


def _bar(view, array, title, position):
    """The colour bar of `array`, titled, at `position` (fractions of the view)."""
    bar = GetScalarBar(GetColorTransferFunction(array), view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.WindowLocation = "Any Location"
    bar.Position = position
    bar.Orientation = "Horizontal"
    bar.ScalarBarLength = 0.3
    bar.TitleFontSize = 14
    bar.LabelFontSize = 12
    bar.RangeLabelFormat = "%-#.3g"
    bar.Visibility = 1


def _flat(reader):
    """True if every point has z = 0 (a 2D run)."""
    bounds = reader.GetDataInformation().GetBounds()
    return bounds[4] == 0.0 and bounds[5] == 0.0


if __name__ == "__main__":
    run = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("HVI_RUN", ".")
    wanted = os.environ.get("HVI_TIME")
    opened = open_run(run, float(os.environ.get("HVI_WARP_SCALE", "1")), float(wanted) if wanted else None)
    if len(sys.argv) > 1:
        target = opened["layout"] if opened["layout"] is not None else opened["view"]
        png = os.path.join(run, "paraview.png")
        SaveScreenshot(png, target, ImageResolution=[1400, 600])
        print("wrote", png)
        sys.stdout.flush()
        os._exit(0)  # Debian's pvpython 5.11 may crash tearing down its windows under Xvfb
