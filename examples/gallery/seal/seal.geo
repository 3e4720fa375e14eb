// A rubber face seal of two materials, axisymmetric (docs/method.md §8.6: x = r, y = z): the
// meridian section of a steel flange with a rectangular groove in its lower face and an elastomer
// ring (a rectangular gasket with rounded lower corners) bonded to the groove's bottom, protruding
// 1 below the flange and touching a rigid flat counter-face (the plane y = −1, not meshed: the
// scene's obstacle) along its lower edge. Units: mm.
//
//   gmsh -2 seal.geo -format msh41 -o seal.msh        (seal.msh: gmsh 4.15.2, 4 749 nodes)
//
// One body, one conforming mesh: the seal and the steel share the nodes of the groove's bottom
// (hvi has no contact between two bodies; the bond is the shared curve). Quadrilaterals only
// (Frontal-Delaunay for quads, then each cell subdivided: the sizes below are halved), so that
// the nearly incompressible elastomer takes mean dilatation per cell with a pressure that does
// not oscillate (docs/method.md §8.4).
//
// Parameters (override with -setnumber; the mesh sizes before the subdivision):
//   hs  element size in the seal                                   (default 0.12)
//   hc  element size far from the seal, in the steel               (default 0.6)
//
// Physical groups:
//   Curve   "Top"     1  the flange's top y = 3.5 (pushed down by the prescribed u_y, u_r = 0)
//   Curve   "Gamma3"  2  the seal's lower edge: the two rounded corners and the flat between
//                        (contact with the counter-face)
//   Curve   "Free"    3  the rest of the boundary (traction free)
//   Surface "Steel"   4  the flange
//   Surface "Seal"    5  the elastomer ring

DefineConstant[ hs = 0.12 ];
DefineConstant[ hc = 0.6 ];
r0 = 22; r1 = 30; top = 3.5;      // the flange's section
g0 = 24; g1 = 28; depth = 2;      // the groove: 24 < r < 28, 0 < y < 2
s0 = 24.5; s1 = 27.5; low = -1;   // the seal: 24.5 < r < 27.5, −1 < y < 2
rc = 0.75;                        // the radius of the seal's lower corners

// the flange (its lower face at y = 0, the groove cut into it)
Point(1) = {r0, 0, 0, hc};
Point(2) = {g0, 0, 0, hs};
Point(3) = {g0, depth, 0, hs};
Point(4) = {s0, depth, 0, hs};
Point(5) = {s1, depth, 0, hs};
Point(6) = {g1, depth, 0, hs};
Point(7) = {g1, 0, 0, hs};
Point(8) = {r1, 0, 0, hc};
Point(9) = {r1, top, 0, hc};
Point(10) = {r0, top, 0, hc};
// the seal below the groove's bottom (points 4 and 5 shared)
Point(11) = {s0, low + rc, 0, hs};
Point(12) = {s0 + rc, low + rc, 0, hs};   // centre of the left corner
Point(13) = {s0 + rc, low, 0, hs};
Point(14) = {s1 - rc, low, 0, hs};
Point(15) = {s1 - rc, low + rc, 0, hs};   // centre of the right corner
Point(16) = {s1, low + rc, 0, hs};

Line(1) = {1, 2};      // flange face, inner
Line(2) = {2, 3};      // groove wall, inner
Line(3) = {3, 4};      // groove bottom, inner gap
Line(4) = {4, 5};      // groove bottom under the seal: the bond
Line(5) = {5, 6};      // groove bottom, outer gap
Line(6) = {6, 7};      // groove wall, outer
Line(7) = {7, 8};      // flange face, outer
Line(8) = {8, 9};      // flange, outer side
Line(9) = {9, 10};     // flange top
Line(10) = {10, 1};    // flange, inner side
Line(11) = {4, 11};    // seal, inner side
Circle(12) = {11, 12, 13};
Line(13) = {13, 14};   // seal, flat of the lower edge
Circle(14) = {14, 15, 16};
Line(15) = {16, 5};    // seal, outer side

Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
Plane Surface(1) = {1};
Curve Loop(2) = {11, 12, 13, 14, 15, -4};
Plane Surface(2) = {2};

// hs in the seal and along the groove, growing to hc at distance 2.5 in the steel
Field[1] = Distance;
Field[1].CurvesList = {2, 3, 4, 5, 6, 11, 12, 13, 14, 15};
Field[1].Sampling = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hs;
Field[2].SizeMax = hc;
Field[2].DistMin = 0.3;
Field[2].DistMax = 2.5;
Field[3] = Constant;
Field[3].VIn = hs;
Field[3].SurfacesList = {2};
Field[4] = Min;
Field[4].FieldsList = {2, 3};
Background Field = 4;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.RecombineAll = 1;
Mesh.Algorithm = 8;
Mesh.SubdivisionAlgorithm = 1;

Physical Curve("Top", 1) = {9};
Physical Curve("Gamma3", 2) = {12, 13, 14};
Physical Curve("Free", 3) = {1, 2, 3, 5, 6, 7, 8, 10, 11, 15};
Physical Surface("Steel", 4) = {1};
Physical Surface("Seal", 5) = {2};
