// Cook's membrane: the tapered panel with corners (0,0), (48,44), (48,60), (0,44), clamped on its
// left edge x = 0 and loaded by a uniform vertical shear on its right edge x = 48 (tests/cook.rs,
// docs/method.md §8.4). Structured (transfinite): n cells along each of the four edges, so the
// meshes for n, 2n, 4n, ... are nested.
//
//   gmsh -2 cook.geo -setnumber n 16 -setnumber quads 1 -format msh41 -o cook/cook_q1_n16.msh
//
// Parameters (override with -setnumber):
//   n      cells per edge                                          (default 8)
//   quads  1 = recombined quadrilaterals (Q1), 0 = triangles (P1)  (default 1)
//
// Physical groups (the tags a scene refers to):
//   Curve   "Gamma1" 1  left edge x = 0, (0,0)–(0,44) (clamped)
//   Curve   "Gamma2" 2  right edge x = 48, (48,44)–(48,60) (loaded: the shear traction)
//   Curve   "Sides"  6  the slanted bottom (0,0)–(48,44) and top (0,44)–(48,60) (traction free)
//   Surface "Omega"  5  the body
// The tip, where the deflection is read, is the corner (48,60), a node of every mesh.

DefineConstant[ n = 8, quads = 1 ];

Point(1) = {0, 0, 0};
Point(2) = {48, 44, 0};
Point(3) = {48, 60, 0};
Point(4) = {0, 44, 0};

Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right (loaded)
Line(3) = {3, 4};   // top
Line(4) = {4, 1};   // left (clamped)
Curve Loop(1) = {1, 2, 3, 4};  // counter-clockwise: surface normal +z
Plane Surface(1) = {1};
Transfinite Curve{1, 2, 3, 4} = n + 1;
Transfinite Surface{1};
If (quads == 1)
  Recombine Surface{1};
EndIf

Physical Curve("Gamma1", 1) = {4};
Physical Curve("Gamma2", 2) = {2};
Physical Curve("Sides", 6) = {1, 3};
Physical Surface("Omega", 5) = {1};
