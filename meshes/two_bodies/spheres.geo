// Two elastic spheres touching at a point (3D; tests/two_body_hertz.rs): the lower one of radius
// R1 centred at (0, 0, −R1), the upper one of radius R2 centred at (0, 0, R2), touching at the
// origin. By symmetry about the planes x = 0 and y = 0, and cut through their centres, each body
// is a quarter of a hemisphere: the lower one x, y > 0, z > −R1, the upper one x, y > 0, z < R2.
// Each is split into a column r < c under its contact patch and the rest (meshed conformally,
// the inner faces in no group), so that the patch r < c of the sphere is a surface of its own.
// The two bodies share no node (each has its own point at the origin). Tetrahedra, refined near
// the contact (OpenCASCADE kernel).
//
//   gmsh -3 spheres.geo -format msh41 -o spheres_p1.msh
//
// Parameters (override with -setnumber):
//   hf   element size within df of the contact point                   (default 0.01 = a/10)
//   hc   element size far from it (at distance dc and beyond)          (default 0.4)
//   df   radius of the zone of size hf around the contact point         (default 0.15)
//   dc   distance at which the size reaches hc                          (default 2)
//   cs   the lower (slave) patch is r < cs                              (default 0.2 = 2a)
//   cm   the upper (master) patch is r < cm                             (default 0.3 = 3a)
// (R1 = R2 = 2; a = 0.1 is the contact radius of the test's load.)
//
// Physical groups (surfaces picked by bounding boxes):
//   Surface "LowerContact" 1  the lower sphere's patch r < cs (the slave surface)
//   Surface "LowerFree"    2  the rest of the lower sphere (traction free)
//   Surface "LowerBase"    3  z = −R1, the lower body's cut (held: u_z = 0)
//   Surface "UpperContact" 4  the upper sphere's patch r < cm (the master surface)
//   Surface "UpperFree"    5  the rest of the upper sphere (traction free)
//   Surface "UpperTop"     6  z = R2, the upper body's cut (pressed down)
//   Surface "SymX"         7  x = 0 of both bodies (u_x = 0)
//   Surface "SymY"         8  y = 0 of both bodies (u_y = 0)
//   Volume  "Lower"        9  the lower body
//   Volume  "Upper"       10  the upper body
//   Volume  "Omega"       11  both

SetFactory("OpenCASCADE");
DefineConstant[ hf = 0.01, hc = 0.4, df = 0.15, dc = 2, cs = 0.2, cm = 0.3 ];
R1 = 2; R2 = 2;
H = 0.1;   // the columns reach from the contact H deep into each body

// the lower body: the quarter hemisphere, split along the cylinder r = cs
Sphere(3) = {0, 0, -R1, R1, 0, Pi / 2, Pi / 2};   // latitudes 0 to π/2, longitudes 0 to π/2
Cylinder(4) = {0, 0, -H, 0, 0, 2 * H, cs};
Cylinder(5) = {0, 0, -H, 0, 0, 2 * H, cs};
BooleanIntersection(6) = { Volume{3}; }{ Volume{4}; Delete; };
BooleanDifference(7) = { Volume{3}; Delete; }{ Volume{5}; Delete; };
lower() = BooleanFragments{ Volume{6, 7}; Delete; }{};

// the upper body, the same about (0, 0, R2), split along r = cm
Sphere(13) = {0, 0, R2, R2, -Pi / 2, 0, Pi / 2};
Cylinder(14) = {0, 0, -H, 0, 0, 2 * H, cm};
Cylinder(15) = {0, 0, -H, 0, 0, 2 * H, cm};
BooleanIntersection(16) = { Volume{13}; }{ Volume{14}; Delete; };
BooleanDifference(17) = { Volume{13}; Delete; }{ Volume{15}; Delete; };
upper() = BooleanFragments{ Volume{16, 17}; Delete; }{};

e = 1e-6;
hs = R1 - Sqrt(R1^2 - cs^2);   // the lower patch's depth
hm = R2 - Sqrt(R2^2 - cm^2);   // the upper patch's height
lowerPatch() = Surface In BoundingBox{-e, -e, -hs - e, cs + e, cs + e, e};
upperPatch() = Surface In BoundingBox{-e, -e, -e, cm + e, cm + e, hm + e};
lowerBase() = Surface In BoundingBox{-e, -e, -R1 - e, R1 + e, R1 + e, -R1 + e};
upperTop() = Surface In BoundingBox{-e, -e, R2 - e, R2 + e, R2 + e, R2 + e};
lowerSymX() = Surface In BoundingBox{-e, -e, -R1 - e, e, R1 + e, e};
lowerSymY() = Surface In BoundingBox{-e, -e, -R1 - e, R1 + e, e, e};
upperSymX() = Surface In BoundingBox{-e, -e, -e, e, R2 + e, R2 + e};
upperSymY() = Surface In BoundingBox{-e, -e, -e, R2 + e, e, R2 + e};
lowerFree() = Abs(CombinedBoundary{ Volume{lower()}; });
lowerFree() -= {lowerPatch(), lowerBase(), lowerSymX(), lowerSymY()};
upperFree() = Abs(CombinedBoundary{ Volume{upper()}; });
upperFree() -= {upperPatch(), upperTop(), upperSymX(), upperSymY()};

// size: hf within df of the contact point, growing to hc at distance dc
origin() = Point In BoundingBox{-e, -e, -e, e, e, e};
Field[1] = Distance;
Field[1].PointsList = {origin()};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = hc;
Field[2].DistMin = df;
Field[2].DistMax = dc;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("LowerContact", 1) = {lowerPatch()};
Physical Surface("LowerFree", 2) = {lowerFree()};
Physical Surface("LowerBase", 3) = {lowerBase()};
Physical Surface("UpperContact", 4) = {upperPatch()};
Physical Surface("UpperFree", 5) = {upperFree()};
Physical Surface("UpperTop", 6) = {upperTop()};
Physical Surface("SymX", 7) = {lowerSymX(), upperSymX()};
Physical Surface("SymY", 8) = {lowerSymY(), upperSymY()};
Physical Volume("Lower", 9) = {lower()};
Physical Volume("Upper", 10) = {upper()};
Physical Volume("Omega", 11) = {lower(), upper()};
