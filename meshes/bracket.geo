// An L-shaped bracket (OpenCASCADE kernel): a base plate resting on the foundation, a vertical
// web rising from its edge x = 0 with a bolt hole through it, a fillet in the inner corner, and
// a load pad at the free end of the base plate's top face.
//
//   gmsh -3 bracket.geo -setnumber lc 0.03 -format msh41 -o bracket_p1.msh
//
// Parameters (override with -setnumber):
//   lc  characteristic length (target tetrahedron edge length)                 (default 0.03)
//   lh  characteristic length on the hole                                      (default lc / 2)
//
// Geometry (lengths in the units of the scene):
//   base plate  (0, 0.8) × (0, 0.6) × (0, 0.1)
//   web         (0, 0.1) × (0, 0.6) × (0, 0.6): 0.1 thick, 0.5 high above the base plate
//   fillet      radius 0.05 along the inner corner x = 0.1, z = 0.1
//   hole        radius 0.08, axis along x through (y, z) = (0.3, 0.4), through the web
//   load pad    the part x > 0.6 of the base plate's top face z = 0.1: the base plate is built
//               from two boxes split at x = 0.6 (two volumes sharing the face x = 0.6, meshed
//               conformally; that inner face is in no group, so it is not saved)
//
// Physical groups (the tags a scene refers to); surfaces are picked by bounding boxes:
//   Surface "Gamma1" 1  the cylindrical surface of the hole (clamped, like a bolt)
//   Surface "Gamma2" 2  the load pad: top face z = 0.1 of the base plate, 0.6 < x < 0.8 (loaded)
//   Surface "Gamma3" 3  the bottom face z = 0 of the base plate (contact with the foundation)
//   Surface "Sides"  6  every other boundary surface (traction free)
//   Volume  "Omega"  5  the body (both volumes)

SetFactory("OpenCASCADE");

DefineConstant[ lc = 0.03 ];
DefineConstant[ lh = lc / 2 ];

Lx = 0.8; Ly = 0.6; tb = 0.1;    // base plate
tw = 0.1; Hw = 0.5;              // web thickness, height above the base plate
rf = 0.05;                       // fillet radius
rh = 0.08; yh = 0.3; zh = 0.4;   // hole radius and axis
xp = 0.6;                        // the load pad is x > xp

// The L: the base plate up to the pad and the web, fused, filleted and drilled.
Box(1) = {0, 0, 0, xp, Ly, tb};
Box(2) = {0, 0, 0, tw, Ly, tb + Hw};
l() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; };
e = 1e-6;
corner() = Curve In BoundingBox{tw - e, -e, tb - e, tw + e, Ly + e, tb + e};
f() = Fillet{l(0)}{corner()}{rf};
Cylinder(10) = {-tw, yh, zh, 3 * tw, 0, 0, rh};
body() = BooleanDifference{ Volume{f()}; Delete; }{ Volume{10}; Delete; };
// The pad: a second box, fragmented with the L so the two share the face x = xp.
Box(20) = {xp, 0, 0, Lx - xp, Ly, tb};
vols() = BooleanFragments{ Volume{body()}; Delete; }{ Volume{20}; Delete; };

hole() = Surface In BoundingBox{-e, yh - rh - e, zh - rh - e, tw + e, yh + rh + e, zh + rh + e};
pad() = Surface In BoundingBox{xp - e, -e, tb - e, Lx + e, Ly + e, tb + e};
bottom() = Surface In BoundingBox{-e, -e, -e, Lx + e, Ly + e, e};
outer() = Abs(CombinedBoundary{ Volume{vols()}; });
sides() = outer();
sides() -= {hole(), pad(), bottom()};

Physical Surface("Gamma1", 1) = {hole()};
Physical Surface("Gamma2", 2) = {pad()};
Physical Surface("Gamma3", 3) = {bottom()};
Physical Surface("Sides", 6) = {sides()};
Physical Volume("Omega", 5) = {vols()};

MeshSize{ PointsOf{ Volume{vols()}; } } = lc;
MeshSize{ PointsOf{ Surface{hole()}; } } = lh;
