// 3D Hertz contact: the quarter (0, W) × (0, W) × (−H, 0) of a block whose top z = 0 touches a
// rigid sphere of radius R at the origin (the sphere is not meshed: its gap
// g = R − sqrt(R² − x² − y²) is the scene's contact.bound). Tetrahedra, refined near the
// contact (OpenCASCADE kernel).
//
//   gmsh -3 hertz_3d.geo -format msh41 -o hertz_3d.msh
//
// Parameters (override with -setnumber):
//   hf  element size on and near the contact patch                (default 0.007 = a/14)
//   hc  element size far from it                                  (default 0.3)
//
// Physical groups (surfaces picked by bounding boxes):
//   Surface "Gamma3"  3  the top patch 0 < x, y < c (contact; c = 0.16 for the scene's push)
//   Surface "SymX"    4  x = 0 (u_x = 0)
//   Surface "SymY"    5  y = 0 (u_y = 0)
//   Surface "Base"    6  z = −H (pushed up by the prescribed u_z)
//   Surface "Free"    7  the rest of the top and the sides x = W, y = W (traction free)
//   Volume  "Omega"   8  the body

SetFactory("OpenCASCADE");
DefineConstant[ hf = 0.007 ];
DefineConstant[ hc = 0.3 ];
W = 1.5; H = 1.5; c = 0.16;

Box(1) = {0, 0, -H, W, W, H};
Rectangle(10) = {0, 0, 0, c, c};
v() = BooleanFragments{ Volume{1}; Delete; }{ Surface{10}; Delete; };

e = 1e-6;
patch() = Surface In BoundingBox{-e, -e, -e, c + e, c + e, e};
top() = Surface In BoundingBox{-e, -e, -e, W + e, W + e, e};
symx() = Surface In BoundingBox{-e, -e, -H - e, e, W + e, e};
symy() = Surface In BoundingBox{-e, -e, -H - e, W + e, e, e};
base() = Surface In BoundingBox{-e, -e, -H - e, W + e, W + e, -H + e};
sidex() = Surface In BoundingBox{W - e, -e, -H - e, W + e, W + e, e};
sidey() = Surface In BoundingBox{-e, W - e, -H - e, W + e, W + e, e};
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
Physical Surface("SymX", 4) = {symx()};
Physical Surface("SymY", 5) = {symy()};
Physical Surface("Base", 6) = {base()};
Physical Surface("Free", 7) = {rest(), sidex(), sidey()};
Physical Volume("Omega", 8) = {v()};
