// Quarter of a thick-walled cylinder: a <= r <= b, 0 <= θ <= π/2 (the Lamé problem; tests/pressure.rs,
// examples/ring.toml). Structured: n cells across the wall, 2n along the quarter arc.
//   gmsh -2 ring.geo -setnumber n 8 -setnumber quads 1 -format msh41 -o ring_q1_n8.msh
// Parameters (-setnumber): n (default 4), quads 1 = Q1 (recombined), 0 = P1 triangles.
// Physical groups:
//   Curve "Inner" 1  r = a, the pressurised bore
//   Curve "Outer" 2  r = b, traction-free
//   Curve "SymX"  3  x = 0 (symmetry: u_x = 0)
//   Curve "SymY"  4  y = 0 (symmetry: u_y = 0)
//   Surface "Omega" 5
If (!Exists(n))
  n = 4;
EndIf
If (!Exists(quads))
  quads = 1;
EndIf
a = 1.0;
b = 2.0;
Point(1) = {0, 0, 0};
Point(2) = {a, 0, 0};
Point(3) = {b, 0, 0};
Point(4) = {0, b, 0};
Point(5) = {0, a, 0};
Line(1) = {2, 3};          // y = 0
Circle(2) = {3, 1, 4};     // r = b
Line(3) = {4, 5};          // x = 0
Circle(4) = {5, 1, 2};     // r = a
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = n + 1;
Transfinite Curve{2, 4} = 2 * n + 1;
Transfinite Surface{1};
If (quads == 1)
  Recombine Surface{1};
EndIf
Physical Curve("Inner", 1) = {4};
Physical Curve("Outer", 2) = {2};
Physical Curve("SymX", 3) = {3};
Physical Curve("SymY", 4) = {1};
Physical Surface("Omega", 5) = {1};
