// 2D Hertz contact, plane strain: the symmetry half (0, W) × (−H, 0) of a block whose top
// y = 0 touches a rigid cylinder of radius R at the origin (the cylinder is not meshed: its gap
// g(x) = R − sqrt(R² − x²) is the scene's contact.bound). Triangles, refined near the contact.
//
//   gmsh -2 hertz_2d.geo -setnumber hf 0.0025 -format msh41 -o hertz_2d_h2.msh
//
// Quadrilaterals of half that size (hertz_2d_q3.msh, the nearly incompressible test of
// tests/hertz.rs; gmsh 4.15.2):
//
//   gmsh -2 hertz_2d.geo -setnumber hf 0.0025 -string "Mesh.RecombineAll = 1; Mesh.Algorithm = 8;
//        Mesh.SubdivisionAlgorithm = 1;" -format msh41 -o hertz_2d_q3.msh
//
// Parameters (override with -setnumber):
//   hf  element size on and near the contact segment              (default 0.0025 = a/20)
//   hc  element size far from it                                  (default 0.2)
//
// Physical groups:
//   Curve   "Gamma3"   3  the top 0 < x < c (contact; c = 0.1 = 2a for the scene's push)
//   Curve   "Symmetry" 4  x = 0 (u_x = 0)
//   Curve   "Base"     5  y = −H (pushed up by the prescribed u_y)
//   Curve   "Free"     6  the rest of the top and the side x = W (traction free)
//   Surface "Omega"    7  the body

DefineConstant[ hf = 0.0025 ];
DefineConstant[ hc = 0.2 ];
W = 2; H = 2; c = 0.1;

Point(1) = {0, -H, 0, hc};
Point(2) = {W, -H, 0, hc};
Point(3) = {W, 0, 0, hc};
Point(4) = {c, 0, 0, hf};
Point(5) = {0, 0, 0, hf};
Line(1) = {1, 2};   // base
Line(2) = {2, 3};   // side x = W
Line(3) = {3, 4};   // free top
Line(4) = {4, 5};   // contact top
Line(5) = {5, 1};   // symmetry
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

// size: hf within 0.02 of the contact segment, growing to hc at distance 1.5
Field[1] = Distance;
Field[1].CurvesList = {4};
Field[1].Sampling = 400;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = hc;
Field[2].DistMin = 0.02;
Field[2].DistMax = 1.5;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Curve("Gamma3", 3) = {4};
Physical Curve("Symmetry", 4) = {5};
Physical Curve("Base", 5) = {1};
Physical Curve("Free", 6) = {2, 3};
Physical Surface("Omega", 7) = {1};
