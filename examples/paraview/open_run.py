"""Open an hvi run in ParaView: the body warped by its displacement and coloured by von Mises,
and the contact boundary Gamma3 coloured by its normal displacement u_nu, at the run's times.

    pvpython examples/paraview/open_run.py RUN_DIR            # renders RUN_DIR/paraview.png
    paraview --script=examples/paraview/open_run.py            # (RUN_DIR from HVI_RUN, default .)

RUN_DIR is an output directory of `hvi solve` (solution.pvd, contact.pvd). The arrays are
described in README.md, "Outputs"; the warp is the displacement times SCALE (default 1, set
HVI_WARP_SCALE to magnify a small-strain run).
"""

import os
import sys

from paraview.simple import (  # noqa: F401  (pvpython provides paraview.simple)
    ColorBy,
    GetActiveViewOrCreate,
    GetAnimationScene,
    PVDReader,
    Render,
    ResetCamera,
    SaveScreenshot,
    Show,
    WarpByVector,
)


def open_run(run_dir, scale=1.0):
    """Loads solution.pvd (and contact.pvd if present); returns the view."""
    view = GetActiveViewOrCreate("RenderView")
    body = PVDReader(FileName=os.path.join(run_dir, "solution.pvd"))
    warped = WarpByVector(Input=body)
    warped.Vectors = ["POINTS", "displacement"]
    warped.ScaleFactor = scale
    shown = Show(warped, view)
    ColorBy(shown, ("POINTS", "von_mises"))
    shown.SetScalarBarVisibility(view, True)
    contact_pvd = os.path.join(run_dir, "contact.pvd")
    if os.path.exists(contact_pvd):
        contact = PVDReader(FileName=contact_pvd)
        # the contact dataset carries the displacement of its nodes: warped like the body
        cwarped = WarpByVector(Input=contact)
        cwarped.Vectors = ["POINTS", "displacement"]
        cwarped.ScaleFactor = scale
        cshown = Show(cwarped, view)
        ColorBy(cshown, ("POINTS", "u_nu"))
        cshown.LineWidth = 4.0
        cshown.SetScalarBarVisibility(view, True)
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = scene.EndTime
    shown.RescaleTransferFunctionToDataRange(False, True)
    view.InteractionMode = "2D" if _flat(body) else "3D"
    ResetCamera(view)
    Render(view)
    return view


def _flat(reader):
    """True if every point has z = 0 (a 2D run)."""
    bounds = reader.GetDataInformation().GetBounds()
    return bounds[4] == 0.0 and bounds[5] == 0.0


if __name__ == "__main__":
    run = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("HVI_RUN", ".")
    view = open_run(run, float(os.environ.get("HVI_WARP_SCALE", "1")))
    if len(sys.argv) > 1:
        SaveScreenshot(os.path.join(run, "paraview.png"), view, ImageResolution=[1200, 700])
        print("wrote", os.path.join(run, "paraview.png"))
