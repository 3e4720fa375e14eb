// Spherical indentation of a gel, axisymmetric: the meridian section (0, W) × (−H, 0) (x = r,
// y = z) of a cylindrical gel block whose top y = 0 touches a rigid sphere of radius R = 1 at
// the origin (the sphere is not meshed: its gap R − sqrt(R² − r²) is the scene's contact.bound).
// Quadrilaterals (gmsh's subdivision halves the sizes below), graded about the origin so that
// the contact edge is resolved by ~2q cells of its radius ρ whether the contact is small (the
// instant response, a = 0.0146) or has crept 4.5× wider, and coarsening fast beyond 1.5 c
// (13 115 nodes; gmsh 4.15.2):
//
//   gmsh -2 gel.geo -format msh41 -o gel.msh
//
// Parameters (override with -setnumber):
//   q     the size is ρ/q before subdivision near the contact        (default 25: a/50 after)
//   hmin  smallest size before subdivision, at the origin            (default 0.0006)
//   hc    largest size before subdivision, far from the contact      (default 0.25)
//
// Physical groups:
//   Curve   "Gamma3"   3  the top 0 < r < c (contact; c = 0.12, 1.8× the crept radius)
//   Curve   "Axis"     4  r = 0 (u_r = 0 there by itself)
//   Curve   "Base"     5  z = −H (pushed up by force control)
//   Curve   "Free"     6  the rest of the top and the side r = W (traction free)
//   Surface "Gel"      7  the body

DefineConstant[ q = 25 ];
DefineConstant[ hmin = 0.0006 ];
DefineConstant[ hc = 0.25 ];
W = 2; H = 2; c = 0.12;

Point(1) = {0, -H, 0, hc};
Point(2) = {W, -H, 0, hc};
Point(3) = {W, 0, 0, hc};
Point(4) = {c, 0, 0, hc};
Point(5) = {0, 0, 0, hc};
Line(1) = {1, 2};   // base
Line(2) = {2, 3};   // side r = W
Line(3) = {3, 4};   // free top
Line(4) = {4, 5};   // contact top
Line(5) = {5, 1};   // axis
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, Max(%g, Sqrt(x*x + y*y) / %g) + 0.3 * Max(0, Sqrt(x*x + y*y) - %g))", hc, hmin, q, 1.5 * c);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.RecombineAll = 1;
Mesh.Algorithm = 8;
Mesh.SubdivisionAlgorithm = 1;

Physical Curve("Gamma3", 3) = {4};
Physical Curve("Axis", 4) = {5};
Physical Curve("Base", 5) = {1};
Physical Curve("Free", 6) = {2, 3};
Physical Surface("Gel", 7) = {1};
