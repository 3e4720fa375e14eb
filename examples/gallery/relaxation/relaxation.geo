// A viscoelastic pad bonded to a rigid base and held pressed against a rigid cylinder (plane
// strain): the symmetry half (0, W) × (−H, 0) of the pad, whose top y = 0 touches the cylinder of
// radius R = 1 at the origin (the cylinder is not meshed: its gap g(x) = R − sqrt(R² − x²) is the
// scene's contact.bound). Triangles, refined near the contact.
//
//   gmsh -2 relaxation.geo -format msh41 -o relaxation.msh
//
// Parameters (override with -setnumber):
//   hf  element size on and near the contact segment              (default 0.004)
//   hc  element size far from it                                  (default 0.1)
//
// Physical groups:
//   Curve   "Gamma3"   3  the top 0 < x < c (contact; c = 0.15, about twice the contact half-width)
//   Curve   "Symmetry" 4  x = 0 (u_x = 0)
//   Curve   "Base"     5  y = −H (bonded to the rigid base, which is pushed up by δ)
//   Curve   "Free"     6  the rest of the top and the side x = W (traction free)
//   Surface "Omega"    7  the pad

DefineConstant[ hf = 0.004 ];
DefineConstant[ hc = 0.1 ];
W = 1; H = 0.5; c = 0.15;

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

// size: hf within 0.02 of the contact segment, growing to hc at distance 0.5
Field[1] = Distance;
Field[1].CurvesList = {4};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = hc;
Field[2].DistMin = 0.02;
Field[2].DistMax = 0.5;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Curve("Gamma3", 3) = {4};
Physical Curve("Symmetry", 4) = {5};
Physical Curve("Base", 5) = {1};
Physical Curve("Free", 6) = {2, 3};
Physical Surface("Omega", 7) = {1};
