// Two contact zones: an arched beam (0, 4) × (0, 1.2) with a half-disc of radius 0.8 cut out
// under its middle, clamped at x = 0, loaded by a pressure on its top. It stands on two feet:
// the left foot on a compliant layer glued to the ground (the paper's law, with a bound), the
// right foot above a rigid roller coated with a thin compliant layer, at an initial gap. The
// roller (a circle obstacle) is not meshed: the scene gives it (two_zones.toml).
//
//   gmsh -2 two_zones.geo -format msh41 -o two_zones.msh
//
// Parameters (override with -setnumber):
//   h   element size away from the right foot          (default 0.05)
//   hf  element size on and near the right foot        (default 0.02)
//
// Physical groups:
//   Curve   "Clamp"      1  x = 0 (clamped)
//   Curve   "LeftFoot"   2  y = 0, 0 < x < 1.2 (on the layer)
//   Curve   "RightFoot"  3  y = 0, 2.8 < x < 4 (over the roller)
//   Curve   "Top"        4  y = 1.2 (the pressure)
//   Curve   "Free"       5  the arch's underside and the end x = 4 (traction free)
//   Surface "Omega"      6  the body

DefineConstant[ h = 0.05 ];
DefineConstant[ hf = 0.02 ];
L = 4; H = 1.2; R = 0.8; xc = 2;

Point(1) = {0, 0, 0, h};
Point(2) = {xc - R, 0, 0, h};
Point(3) = {xc, 0, 0, h};          // the arch's centre
Point(4) = {xc + R, 0, 0, hf};
Point(5) = {L, 0, 0, hf};
Point(6) = {L, H, 0, h};
Point(7) = {0, H, 0, h};
Point(8) = {xc, R, 0, h};          // the crown of the arch
Line(1) = {1, 2};                  // left foot
Circle(2) = {2, 3, 8};             // the arch, in two quarter circles (a half circle is ambiguous)
Circle(7) = {8, 3, 4};
Line(3) = {4, 5};                  // right foot
Line(4) = {5, 6};                  // free end
Line(5) = {6, 7};                  // top
Line(6) = {7, 1};                  // clamp
Curve Loop(1) = {1, 2, 7, 3, 4, 5, 6};
Plane Surface(1) = {1};

// hf within 0.1 of the right foot, growing to h at distance 0.5
Field[1] = Distance;
Field[1].CurvesList = {3};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = h;
Field[2].DistMin = 0.1;
Field[2].DistMax = 0.5;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
// quadrilaterals (Q1)
Recombine Surface{1};
Mesh.Algorithm = 8;
Mesh.RecombinationAlgorithm = 2;

Physical Curve("Clamp", 1) = {6};
Physical Curve("LeftFoot", 2) = {1};
Physical Curve("RightFoot", 3) = {3};
Physical Curve("Top", 4) = {5};
Physical Curve("Free", 5) = {2, 7, 4};
Physical Surface("Omega", 6) = {1};
