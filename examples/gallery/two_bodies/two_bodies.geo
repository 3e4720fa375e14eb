// Two deformable bodies of one mesh (2D, plane strain; docs/gallery.md, "Two deformable bodies: a
// steel punch on a relaxing pad"): a steel punch with a rounded nose, the lower half of the disk
// of radius R = 1 centred at (0, 1), resting on a polymer pad (−W, W) × (−H, 0) whose top it
// touches at the origin. The bodies share no node (Geometry.AutoCoherence = 0); their contact is
// the scene's [[contact]] pair, the punch's nose (slave) against the pad's top under it (master).
//
//   gmsh -2 two_bodies.geo -format msh41 -o two_bodies.msh        (gmsh 4.15.2)
//
// Non-matching meshes: triangles in the punch, hp along its nose; quadrilaterals in the pad
// (Frontal-Delaunay for quads, then recombined), hq along its top under the nose, finer than the
// punch's; both growing to hc at distance dc (1 495 nodes: the punch's 963 triangles, the pad's
// 883 quadrilaterals and 2 triangles). The slave side (the punch) is the coarser one: a nearly
// rigid slave finer than its soft master has more rows than the master has nodes to satisfy them
// with, and its contact pressure oscillates from node to node (docs/gallery.md).
//
// Parameters (override with -setnumber):
//   hq  element size along the pad's top, |x| < c                    (default 0.01)
//   hp  element size along the punch's nose, |x| < c (rounded to an odd number of segments)
//                                                                    (default 0.015)
//   hc  element size far from the contact                            (default 0.2)
//   dc  distance from the contact zone at which the size reaches hc  (default 1.2)
//
// Physical groups:
//   Curve   "PunchTop"     1  y = R, the punch's flat top (moved: pressed down, then sideways)
//   Curve   "PunchNose"    2  the arc |x| < c = 0.3 (the slave surface)
//   Curve   "PunchFree"    3  the rest of the arc (traction free)
//   Curve   "PadTop"       4  the pad's top |x| < c (the master surface)
//   Curve   "PadFree"      5  the rest of the pad's top and its sides x = ±W (traction free)
//   Curve   "PadBottom"    6  y = −H (clamped: bonded to a rigid base)
//   Surface "Punch"        7  the punch (steel, elastic)
//   Surface "Pad"          8  the pad (viscoelastic)

Geometry.AutoCoherence = 0;
DefineConstant[ hq = 0.01, hp = 0.015, hc = 0.2, dc = 1.2 ];
R = 1; W = 3; H = 1; c = 0.3;
yc = R - Sqrt(R^2 - c^2);           // height of the nose's ends

// the punch: the arc from (−R, R) down past the origin to (R, R), closed by its top. The nose is
// one arc cut in an odd number of segments, so that no punch node lies at the origin, where the
// pad has one: `hvi plot` places gamma3.csv's rows on the mesh by their position, and a punch
// node on a pad node would be taken for the pad's.
Point(1) = {0, R, 0};               // centre
Point(2) = {-R, R, 0};
Point(3) = {-c, yc, 0};
Point(5) = {c, yc, 0};
Point(6) = {R, R, 0};
Circle(1) = {2, 1, 3};              // free arc, left
Circle(2) = {3, 1, 5};              // nose
Circle(4) = {5, 1, 6};              // free arc, right
Line(5) = {6, 2};                   // top
Curve Loop(1) = {1, 2, 4, 5};       // counter-clockwise
Plane Surface(1) = {1};
Transfinite Curve{2} = 2 * Round(R * Asin(c / R) / hp) + 2;

// the pad, its top split at the origin (a node under the nose's lowest point) and at x = ±c
Point(11) = {-W, -H, 0};
Point(12) = {W, -H, 0};
Point(13) = {W, 0, 0};
Point(14) = {c, 0, 0};
Point(15) = {0, 0, 0};
Point(16) = {-c, 0, 0};
Point(17) = {-W, 0, 0};
Line(11) = {11, 12};                // bottom
Line(12) = {12, 13};                // right side
Line(13) = {13, 14};                // top, right of the contact zone
Line(14) = {14, 15};                // top under the nose, right half
Line(15) = {15, 16};                // top under the nose, left half
Line(16) = {16, 17};                // top, left of the contact zone
Line(17) = {17, 11};                // left side
Curve Loop(2) = {11, 12, 13, 14, 15, 16, 17};
Plane Surface(2) = {2};

// sizes: in each body, its own contact size on its contact curves, growing to hc at distance dc
Field[1] = Distance;
Field[1].CurvesList = {2};
Field[1].Sampling = 400;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hp;
Field[2].SizeMax = hc;
Field[2].DistMin = 0.02;
Field[2].DistMax = dc;
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].SurfacesList = {1};
Field[3].CurvesList = {1, 2, 4, 5};
Field[4] = Distance;
Field[4].CurvesList = {14, 15};
Field[4].Sampling = 400;
Field[5] = Threshold;
Field[5].InField = 4;
Field[5].SizeMin = hq;
Field[5].SizeMax = hc;
Field[5].DistMin = 0.02;
Field[5].DistMax = dc;
Field[6] = Restrict;
Field[6].InField = 5;
Field[6].SurfacesList = {2};
Field[6].CurvesList = {11, 12, 13, 14, 15, 16, 17};
Field[7] = Min;
Field[7].FieldsList = {3, 6};
Background Field = 7;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 8;
Recombine Surface{2};

Physical Curve("PunchTop", 1) = {5};
Physical Curve("PunchNose", 2) = {2};
Physical Curve("PunchFree", 3) = {1, 4};
Physical Curve("PadTop", 4) = {14, 15};
Physical Curve("PadFree", 5) = {12, 13, 16, 17};
Physical Curve("PadBottom", 6) = {11};
Physical Surface("Punch", 7) = {1};
Physical Surface("Pad", 8) = {2};
