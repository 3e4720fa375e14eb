// 3D Cattaneo–Mindlin: the half (−W, W) × (0, W) × (−H, 0) of a block whose top z = 0 touches a
// rigid sphere of radius R = 1 at the origin (the sphere is the scene's contact.bound, the gap
// g = R − sqrt(R² − x² − y²)). The block is pressed, then sheared along x, so y = 0 is its only
// symmetry plane. Tetrahedra, refined near the contact (OpenCASCADE kernel).
//
//   gmsh -3 cattaneo_3d.geo -format msh41 -o cattaneo_3d.msh
//
// Parameters (override with -setnumber):
//   hf  element size on and near the contact patch                (default 0.006 = a/17)
//   hc  element size far from it                                  (default 0.3)
//
// Physical groups (surfaces picked by bounding boxes):
//   Surface "Gamma3"  3  the top patch −c < x < c, 0 < y < c (contact; c = 0.115 for a ≈ 0.104)
//   Surface "SymY"    5  y = 0 (u_y = 0)
//   Surface "Base"    6  z = −H (pressed up, then moved along x)
//   Surface "Free"    7  the rest of the top and the sides x = ±W, y = W (traction free)
//   Volume  "Omega"   8  the body

SetFactory("OpenCASCADE");
DefineConstant[ hf = 0.006 ];
DefineConstant[ hc = 0.3 ];
W = 1.5; H = 1.5; c = 0.115;

Box(1) = {-W, 0, -H, 2 * W, W, H};
Rectangle(10) = {-c, 0, 0, 2 * c, c};
v() = BooleanFragments{ Volume{1}; Delete; }{ Surface{10}; Delete; };

e = 1e-6;
patch() = Surface In BoundingBox{-c - e, -e, -e, c + e, c + e, e};
top() = Surface In BoundingBox{-W - e, -e, -e, W + e, W + e, e};
symy() = Surface In BoundingBox{-W - e, -e, -H - e, W + e, e, e};
base() = Surface In BoundingBox{-W - e, -e, -H - e, W + e, W + e, -H + e};
sidex0() = Surface In BoundingBox{-W - e, -e, -H - e, -W + e, W + e, e};
sidex1() = Surface In BoundingBox{W - e, -e, -H - e, W + e, W + e, e};
sidey() = Surface In BoundingBox{-W - e, W - e, -H - e, W + e, W + e, e};
rest() = {};
For i In {0 : #top() - 1}
  If (top(i) != patch(0))
    rest() += top(i);
  EndIf
EndFor

// size: hf within 0.05 of the patch, growing to hc at distance 1.2
Field[1] = Distance;
Field[1].SurfacesList = {patch()};
Field[1].Sampling = 60;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = hc;
Field[2].DistMin = 0.05;
Field[2].DistMax = 1.2;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("Gamma3", 3) = {patch()};
Physical Surface("SymY", 5) = {symy()};
Physical Surface("Base", 6) = {base()};
Physical Surface("Free", 7) = {rest(), sidex0(), sidex1(), sidey()};
Physical Volume("Omega", 8) = {v()};
