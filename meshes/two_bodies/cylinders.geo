// Two elastic cylinders touching along a line (2D, plane strain; tests/two_body_hertz.rs): the
// lower one of radius R1 = 1 centred at (0, −R1), the upper one of radius R2 = 2 centred at
// (0, R2), touching at the origin. By symmetry about x = 0 and cut through their centres, each
// body is a quarter disk: the lower one x > 0, y > −R1, the upper one x > 0, y < R2. The two
// bodies share no node (Geometry.AutoCoherence = 0: each has its own point at the origin).
// Triangles (or quadrilaterals), refined near the contact.
//
//   gmsh -2 cylinders.geo -format msh41 -o cylinders_p1.msh
//
// Parameters (override with -setnumber):
//   hf     element size within df of the contact point                 (default 0.002 = a/25)
//   hc     element size far from it (at distance 1 and beyond)        (default 0.1)
//   df     radius of the zone of size hf around the contact point       (default 0.1)
//   cs     the lower (slave) contact arc is 0 < x < cs                   (default 0.1 = 2a)
//   cm     the upper (master) contact arc is 0 < x < cm                  (default 0.15 = 3a)
//   quads  1 = recombined quadrilaterals (Q1), 0 = triangles (P1)      (default 0)
// (a = 0.05 is the contact half-width of the test's load.)
//
// Physical groups:
//   Curve   "LowerContact" 1  the lower arc 0 < x < cs (the slave surface)
//   Curve   "LowerFree"    2  the rest of the lower arc (traction free)
//   Curve   "Symmetry"     3  x = 0 of both bodies (u_x = 0)
//   Curve   "LowerBase"    4  y = −R1, the lower body's cut (held: u_y = 0)
//   Curve   "UpperContact" 5  the upper arc 0 < x < cm (the master surface)
//   Curve   "UpperFree"    6  the rest of the upper arc (traction free)
//   Curve   "UpperTop"     7  y = R2, the upper body's cut (pressed down)
//   Surface "Lower"        8  the lower body
//   Surface "Upper"        9  the upper body
//   Surface "Omega"       10  both

Geometry.AutoCoherence = 0;
DefineConstant[ hf = 0.002, hc = 0.1, df = 0.1, cs = 0.1, cm = 0.15, quads = 0 ];
R1 = 1; R2 = 2;

// the lower body
Point(1) = {0, -R1, 0};                        // centre
Point(2) = {R1, -R1, 0};
Point(3) = {cs, -R1 + Sqrt(R1^2 - cs^2), 0};
Point(4) = {0, 0, 0};                          // the contact point
Line(1) = {1, 2};                              // base
Circle(2) = {2, 1, 3};                         // free arc
Circle(3) = {3, 1, 4};                         // contact arc
Line(4) = {4, 1};                              // symmetry
Curve Loop(1) = {1, 2, 3, 4};                  // counter-clockwise
Plane Surface(1) = {1};

// the upper body
Point(11) = {0, R2, 0};                        // centre
Point(12) = {0, 0, 0};                         // the contact point (its own)
Point(13) = {cm, R2 - Sqrt(R2^2 - cm^2), 0};
Point(14) = {R2, R2, 0};
Circle(11) = {12, 11, 13};                     // contact arc
Circle(12) = {13, 11, 14};                     // free arc
Line(13) = {14, 11};                           // top
Line(14) = {11, 12};                           // symmetry
Curve Loop(2) = {11, 12, 13, 14};              // counter-clockwise
Plane Surface(2) = {2};

// size: hf within df of the contact point, growing to hc at distance 1
Field[1] = Distance;
Field[1].PointsList = {4, 12};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = hc;
Field[2].DistMin = df;
Field[2].DistMax = 1;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
If (quads == 1)
  Recombine Surface{1, 2};
EndIf

Physical Curve("LowerContact", 1) = {3};
Physical Curve("LowerFree", 2) = {2};
Physical Curve("Symmetry", 3) = {4, 14};
Physical Curve("LowerBase", 4) = {1};
Physical Curve("UpperContact", 5) = {11};
Physical Curve("UpperFree", 6) = {12};
Physical Curve("UpperTop", 7) = {13};
Physical Surface("Lower", 8) = {1};
Physical Surface("Upper", 9) = {2};
Physical Surface("Omega", 10) = {1, 2};
