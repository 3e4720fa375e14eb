// A block (−1, 1)² × (0, 1) of P1 tetrahedra graded towards the origin, where its bottom face
// z = 0 (the whole face is Γ₃) touches a rigid sphere of radius 1 centred at (0, 0, −1): the mesh
// users make for an indentation (issue 46; benches/graded/README.md).
//
//   gmsh -3 graded_block.geo -setnumber hf 0.008 -format msh41 -o graded_31k.msh
//
// Parameters (override with -setnumber):
//   hf  element size at the origin                                (default 0.008)
//   hc  element size far from it                                  (default 0.25)
//   s   growth of the size with the distance r to the origin: h = min(hc, hf + s r)
//
// Physical groups:
//   Surface "Gamma3"  1  the bottom z = 0 (contact)
//   Surface "Top"     2  z = 1 (pushed down)
//   Surface "Free"    3  the four sides
//   Volume  "Omega"   4  the body

SetFactory("OpenCASCADE");
DefineConstant[ hf = 0.008 ];
DefineConstant[ hc = 0.25 ];
DefineConstant[ s = 0.09 ];

Box(1) = {-1, -1, 0, 2, 2, 1};

e = 1e-6;
bottom() = Surface In BoundingBox{-1 - e, -1 - e, -e, 1 + e, 1 + e, e};
top() = Surface In BoundingBox{-1 - e, -1 - e, 1 - e, 1 + e, 1 + e, 1 + e};
all() = Boundary{ Volume{1}; };
Point(100) = {0, 0, 0, hf};
Point{100} In Surface{bottom(0)};  // the size field is sampled where the mesh has points
sides() = {};
For i In {0 : #all() - 1}
  If (all(i) != bottom(0) && all(i) != top(0))
    sides() += all(i);
  EndIf
EndFor

// h = min(hc, hf + s r): gmsh's MathEval parser mis-reads sqrt, so the distance is a field
Field[1] = Distance;
Field[1].PointsList = {100};
Field[2] = MathEval;
Field[2].F = Sprintf("%.17g + %.17g*F1", hf, s);
Background Field = 2;
Mesh.MeshSizeMax = hc;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm3D = 1;

Physical Surface("Gamma3", 1) = bottom();
Physical Surface("Top", 2) = top();
Physical Surface("Free", 3) = sides();
Physical Volume("Omega", 4) = {1};
