// Cattaneo–Mindlin, 2D plane strain: the whole block (−W, W) × (−H, 0) whose top y = 0 touches a
// rigid cylinder of radius R = 1 at the origin (the scene's contact.bound is the gap), pressed
// by its base and then moved sideways: partial slip at the edges of the contact (tests/friction.rs).
// Triangles, refined near the contact segment |x| < c.
//
//   gmsh -2 cattaneo_2d.geo -format msh41 -o cattaneo_2d.msh
//
// Physical groups: Curve "Gamma3" 3 (the top |x| < c), "Base" 5 (y = −H), "Free" 6 (the rest),
// Surface "Omega" 7.

DefineConstant[ hf = 0.00125 ];
DefineConstant[ hc = 0.2 ];
W = 2; H = 2; c = 0.1;
Point(1) = {-W, -H, 0, hc};
Point(2) = {W, -H, 0, hc};
Point(3) = {W, 0, 0, hc};
Point(4) = {c, 0, 0, hf};
Point(5) = {-c, 0, 0, hf};
Point(6) = {-W, 0, 0, hc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
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
Physical Curve("Base", 5) = {1};
Physical Curve("Free", 6) = {2, 3, 5, 6};
Physical Surface("Omega", 7) = {1};
