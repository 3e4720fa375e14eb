"""Check in ParaView what a user of an hvi run should see (docs/method.md §12.1):

    pvpython examples/paraview/check_run.py RUN_DIR                       # the data, no display needed
    xvfb-run -a pvpython examples/paraview/check_run.py RUN_DIR --render  # and open_run.py's picture

* solution.pvd: the time steps ParaView reports are the .pvd's, every frame's FieldData
  TimeValue is its time, the scene's output.active_scalar (von_mises by default) is the active
  point scalar, displacement the active vector
  (so that Warp By Vector picks it), and the warped body at the last time moves by the largest
  |displacement|;
* contact.pvd: the same times; at the last time its points are the contact nodes gamma3.csv
  lists, with the same u_nu, and the Gamma3 nodes whose normal displacement is prescribed
  (status -1, docs/method.md §7.4); Plot Over Line along Gamma3 (the line open_run.py
  draws) returns u_nu equal to the linear interpolation of the nodal values (exact on a straight
  Gamma3, whose facets are the line's segments); Plot Data on contact.pvd holds u_nu;
* with --render: open_run.py's view is at the last time, coloured by the active scalar over its range
  at that time and Gamma3 by u_nu over its range (not the first frame's), and its picture
  RUN_DIR/paraview.png is written.

Prints one line per check and "ParaView checks: 0 of N failed"; exits 1 if any check fails.
"""

import csv
import math
import os
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from paraview import servermanager  # noqa: E402
from paraview.simple import GetParaViewVersion, PlotData, PlotOverLine, PVDReader, WarpByVector  # noqa: E402
from vtk.numpy_interface import dataset_adapter as dsa  # noqa: E402

RESULTS = []


def check(ok, what):
    RESULTS.append(bool(ok))
    print(("ok   " if ok else "FAIL ") + what)
    return ok


def pvd_times(path):
    """(time, file) of each DataSet of a .pvd, as written."""
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def fetch(proxy, time):
    proxy.UpdatePipeline(time)
    return dsa.WrapDataObject(servermanager.Fetch(proxy))


def gamma3_last(run_dir):
    """The rows of gamma3.csv at its last time: (time, [(point, u_nu)])."""
    with open(os.path.join(run_dir, "gamma3.csv")) as f:
        rows = list(csv.DictReader(f))
    last = float(rows[-1]["time"])
    dims = ["x", "y", "z"] if "z" in rows[0] else ["x", "y"]
    nodes = [
        (tuple(float(r[d]) for d in dims) + (0.0,) * (3 - len(dims)), float(r["u_nu"]))
        for r in rows
        if float(r["time"]) == last
    ]
    return last, nodes


def scene_active_scalar(run_dir):
    """output.active_scalar of the run's scene.toml, von_mises when absent."""
    import tomllib

    with open(os.path.join(run_dir, "scene.toml"), "rb") as f:
        scene = tomllib.load(f)
    return scene.get("output", {}).get("active_scalar", "von_mises")


def check_series(run_dir):
    print("ParaView %s, run %s" % (GetParaViewVersion(), run_dir))
    written = pvd_times(os.path.join(run_dir, "solution.pvd"))
    body = PVDReader(FileName=os.path.join(run_dir, "solution.pvd"))
    reported = list(body.TimestepValues)
    check(
        reported == [t for t, _ in written],
        "solution.pvd: ParaView reports %d times %s (the .pvd lists %d: %s)"
        % (len(reported), _short(reported), len(written), _short([t for t, _ in written])),
    )
    bad = []
    for t in reported:
        d = fetch(body, t)
        if float(d.FieldData["TimeValue"][0]) != t:
            bad.append(t)
    check(not bad, "solution.pvd: every frame's FieldData TimeValue is its time (%d frames)" % len(reported))
    t_last = reported[-1]
    d = fetch(body, t_last)
    pd = d.VTKObject.GetPointData()
    scalars, vectors = pd.GetScalars(), pd.GetVectors()
    wanted = scene_active_scalar(run_dir)
    check(
        scalars is not None and scalars.GetName() == wanted,
        "solution.pvd: the active point scalar is %s (the scene's output.active_scalar: %s)"
        % (scalars.GetName() if scalars else None, wanted),
    )
    check(
        vectors is not None and vectors.GetName() == "displacement",
        "solution.pvd: the active point vector is %s" % (vectors.GetName() if vectors else None),
    )
    u = d.PointData["displacement"]
    umax = float(max(math.sqrt(sum(float(c) ** 2 for c in v)) for v in u))
    warped = WarpByVector(Input=body)  # the vectors it picks by itself
    w = fetch(warped, t_last)
    moved = max(
        math.sqrt(sum((float(a) - float(b)) ** 2 for a, b in zip(p, q))) for p, q in zip(w.Points, d.Points)
    )
    check(
        abs(moved - umax) <= 1e-12 * max(umax, 1e-300),
        "Warp By Vector (default vectors) at t = %g moves the body by %.6g = max |displacement| %.6g"
        % (t_last, moved, umax),
    )
    vm = d.PointData["von_mises"]
    check(
        len(vm) == d.GetNumberOfPoints() and float(min(vm)) >= 0.0,
        "solution.pvd: von_mises at t = %g ranges %.4g … %.4g over %d points"
        % (t_last, float(min(vm)), float(max(vm)), len(vm)),
    )

    contact_pvd = os.path.join(run_dir, "contact.pvd")
    if not os.path.exists(contact_pvd):
        print("(no contact.pvd: the run has no contact groups)")
        return
    contact = PVDReader(FileName=contact_pvd)
    creported = list(contact.TimestepValues)
    check(creported == reported, "contact.pvd: ParaView reports the same %d times" % len(creported))
    c = fetch(contact, t_last)
    csv_time, nodes = gamma3_last(run_dir)
    check(csv_time == t_last, "gamma3.csv ends at t = %g" % csv_time)
    points = [tuple(float(x) for x in p) for p in c.Points]
    size = max(max(abs(x) for x in p) for p in points) or 1.0
    key = {_key(p, size): i for i, p in enumerate(points)}
    matched = [key.get(_key(p, size)) for p, _ in nodes]
    status = [int(v) for v in c.PointData["status"]]
    others = [i for i in range(len(points)) if i not in set(matched)]
    check(
        None not in matched
        and len(set(matched)) == len(nodes)
        and all(status[i] == -1 for i in others)
        and all(status[i] != -1 for i in matched),
        "contact.pvd at t = %g: its %d points are the %d contact nodes of gamma3.csv and %d nodes whose u_nu "
        "is prescribed (status -1)" % (t_last, len(points), len(nodes), len(others)),
    )
    un = [float(v) for v in c.PointData["u_nu"]]
    scale = max(max(abs(v) for v in un), 1e-300)
    if None not in matched:
        diff = max(abs(un[i] - v) for i, (_, v) in zip(matched, nodes))
        # gamma3.csv prints 17 significant digits: the values agree to rounding
        check(diff <= 1e-12 * scale, "contact.pvd u_nu = gamma3.csv u_nu (max |diff| %.1e)" % diff)

    from open_run import gamma3_line

    flat = all(p[2] == 0.0 for p in points)
    ends = gamma3_line(contact.GetDataInformation().GetBounds(), flat)
    line = PlotOverLine(Input=contact)
    line.Point1, line.Point2 = ends
    line.Resolution = 200
    probe = fetch(line, t_last)
    mask = probe.PointData["vtkValidPointMask"]
    s = [float(v) for v in probe.PointData["arc_length"]]
    values = [float(v) for v in probe.PointData["u_nu"]]
    valid = [k for k in range(len(s)) if mask[k]]
    # the nodes on the line, by distance from Point1, and their u_nu linearly interpolated
    p1, p2 = ends
    length = math.sqrt(sum((b - a) ** 2 for a, b in zip(p1, p2)))
    on_line = []
    for i, p in enumerate(points):
        d1 = sum((x - a) * (b - a) for x, a, b in zip(p, p1, p2)) / length
        foot = [a + d1 * (b - a) / length for a, b in zip(p1, p2)]
        if math.sqrt(sum((x - f) ** 2 for x, f in zip(p, foot))) <= 1e-9 * length:
            on_line.append((d1, un[i]))
    on_line.sort()
    err = max(abs(values[k] - _interp(s[k], on_line)) for k in valid) if valid and len(on_line) > 1 else math.inf
    check(
        len(valid) == len(s) and err <= 1e-9 * scale,
        "Plot Over Line along Gamma3 (%s to %s) at t = %g: %d of %d samples on Gamma3, u_nu = the nodal "
        "values interpolated (max |diff| %.1e), u_nu %.4g … %.4g"
        % (_pt(p1), _pt(p2), t_last, len(valid), len(s), err, min(values), max(values)),
    )
    table = fetch(PlotData(Input=contact), t_last)
    check("u_nu" in table.PointData.keys(), "Plot Data on contact.pvd holds u_nu")


def check_render(run_dir):
    from open_run import open_run
    from paraview.simple import GetColorTransferFunction, SaveScreenshot

    opened = open_run(run_dir)
    t_last = opened["times"][-1]
    check(opened["time"] == t_last, "open_run.py shows t = %g (the last time %g)" % (opened["time"], t_last))
    check(
        opened["scalar"] == scene_active_scalar(run_dir),
        "open_run.py colours the body by %s (the scene's output.active_scalar: %s)"
        % (opened["scalar"], scene_active_scalar(run_dir)),
    )
    for array, reader in ((opened["scalar"], opened["body"]), ("u_nu", opened.get("contact"))):
        if reader is None:
            continue
        lo, hi = _range(reader, array, t_last)
        lut = GetColorTransferFunction(array)
        pts = lut.RGBPoints
        check(
            abs(pts[0] - lo) <= 1e-9 * max(abs(hi), 1e-300) and abs(pts[-4] - hi) <= 1e-9 * max(abs(hi), 1e-300),
            "open_run.py colours by %s over %.4g … %.4g (its range at t = %g: %.4g … %.4g)"
            % (array, pts[0], pts[-4], t_last, lo, hi),
        )
    png = os.path.join(run_dir, "paraview.png")
    if os.path.exists(png):
        os.remove(png)
    target = opened["layout"] if opened["layout"] is not None else opened["view"]
    SaveScreenshot(png, target, ImageResolution=[1400, 600])
    check(os.path.exists(png) and os.path.getsize(png) > 10000, "open_run.py's picture %s" % png)


def _range(reader, array, t):
    """The range ParaView colours by: the values, or the magnitudes of a vector or tensor."""
    values = fetch(reader, t).PointData[array]
    if len(values.shape) > 1:
        values = [math.sqrt(sum(float(c) ** 2 for c in v)) for v in values]
    values = [float(v) for v in values]
    return min(values), max(values)


def _interp(x, pts):
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 - 1e-12 <= x <= x1 + 1e-12:
            return y0 if x1 == x0 else y0 + (y1 - y0) * (x - x0) / (x1 - x0)
    return math.inf


def _key(p, size):
    return tuple(round(x / (1e-9 * size)) for x in p)


def _pt(p):
    return "(" + ", ".join("%g" % x for x in p) + ")"


def _short(ts):
    return ", ".join("%g" % t for t in ts) if len(ts) <= 6 else "%g, %g, … %g" % (ts[0], ts[1], ts[-1])


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    run = args[0] if args else "."
    if "--render" in sys.argv:
        # the render views first: with Debian's ParaView 5.11 under Xvfb, a render view created
        # after the data checks' pipelines fails (GLXBadContext)
        check_render(run)
    check_series(run)
    failed = RESULTS.count(False)
    print("ParaView checks: %d of %d failed" % (failed, len(RESULTS)))
    sys.stdout.flush()
    # os._exit: Debian's pvpython 5.11 may crash while tearing down its render windows under
    # Xvfb (SIGSEGV after the last line), which would hide the checks' verdict
    os._exit(1 if failed else 0)
