// The paper's domain Ω = (0,2)×(0,1), meshed with a structured (transfinite) grid.
//
//   gmsh -2 rectangle.geo -setnumber n 16 -setnumber quads 1 -format msh41 -o rect_q1_h16.msh
//   gmsh -2 rectangle.geo -setnumber n 16 -setnumber quads 1 -setnumber plain 1 -format msh41 -o rect_q1_h16_plain.msh
//
// Parameters (override with -setnumber):
//   n      cells per unit length, h = 1/n                                  (default 16)
//   quads  1 = recombined quadrilaterals (Q1), 0 = triangles (P1)          (default 1)
//   wide   1 = cells 2h×h (n parts along each side), 0 = square h×h cells  (default 0)
//   mixed  1 = quadrilaterals on x < 1, triangles on x > 1 (a mixed mesh)  (default 0)
//   halves 1 = two surfaces split at x = 1, each its own physical group     (default 0)
//              (Left 6, Right 7; cells as `quads` says): two materials
//   plain  1 = only the groups the paper names (no Gamma2_top), 0 = all    (default 0)
// The grid points are equally spaced, so the meshes for n, 2n, 4n, ... are nested.
//
// Physical groups (the tags a scene refers to):
//   Curve   "Gamma1"     1  left side x = 0 (clamped)
//   Curve   "Gamma2"     2  right side x = 2 and top y = 1 (loaded)
//   Curve   "Gamma3"     3  bottom y = 0 (contact)
//   Curve   "Gamma2_top" 4  top y = 1 only (its facets are also in Gamma2; not with plain 1)
//   Surface "Omega"      5  the body
//   Surface "Left"       6  x < 1 (halves 1 only)
//   Surface "Right"      7  x > 1 (halves 1 only)
//   Curve   "Gamma2_right" 8  right side x = 2 only (halves 1 only; its facets are also in Gamma2)
// With plain 1 the tags stay as above (Omega is still 5), only Gamma2_top is left out.

DefineConstant[ n = 16, quads = 1, wide = 0, mixed = 0, plain = 0, halves = 0 ];

Lx = 2; Ly = 1;
ny = n;                          // parts along the left/right sides
nx = (wide == 1) ? n : 2 * n;    // parts along the bottom/top sides

Point(1) = {0, 0, 0};
Point(2) = {Lx, 0, 0};
Point(3) = {Lx, Ly, 0};
Point(4) = {0, Ly, 0};

If (mixed == 0 && halves == 0)
  Line(1) = {1, 2};   // bottom
  Line(2) = {2, 3};   // right
  Line(3) = {3, 4};   // top
  Line(4) = {4, 1};   // left
  Curve Loop(1) = {1, 2, 3, 4};  // counter-clockwise: surface normal +z
  Plane Surface(1) = {1};
  Transfinite Curve{1, 3} = nx + 1;
  Transfinite Curve{2, 4} = ny + 1;
  Transfinite Surface{1};
  If (quads == 1)
    Recombine Surface{1};
  EndIf
  Physical Curve("Gamma1", 1) = {4};
  Physical Curve("Gamma2", 2) = {2, 3};
  Physical Curve("Gamma3", 3) = {1};
  If (plain == 0)
    Physical Curve("Gamma2_top", 4) = {3};
  EndIf
  Physical Surface("Omega", 5) = {1};
Else
  // Two surfaces split at x = Lx/2: quads on the left, triangles on the right (mixed), or
  // both as `quads` says, each its own physical group (halves).
  Point(5) = {Lx / 2, 0, 0};
  Point(6) = {Lx / 2, Ly, 0};
  Line(1) = {1, 5};   // bottom, left half
  Line(2) = {5, 2};   // bottom, right half
  Line(3) = {2, 3};   // right
  Line(4) = {3, 6};   // top, right half
  Line(5) = {6, 4};   // top, left half
  Line(6) = {4, 1};   // left
  Line(7) = {5, 6};   // interface x = Lx/2
  Curve Loop(1) = {1, 7, 5, 6};
  Plane Surface(1) = {1};
  Curve Loop(2) = {2, 3, 4, -7};
  Plane Surface(2) = {2};
  Transfinite Curve{1, 2, 4, 5} = nx / 2 + 1;
  Transfinite Curve{3, 6, 7} = ny + 1;
  Transfinite Surface{1};
  Transfinite Surface{2};
  If (mixed == 1 || quads == 1)
    Recombine Surface{1};
  EndIf
  If (halves == 1 && quads == 1)
    Recombine Surface{2};
  EndIf
  Physical Curve("Gamma1", 1) = {6};
  Physical Curve("Gamma2", 2) = {3, 4, 5};
  Physical Curve("Gamma3", 3) = {1, 2};
  If (plain == 0)
    Physical Curve("Gamma2_top", 4) = {4, 5};
  EndIf
  Physical Surface("Omega", 5) = {1, 2};
  If (halves == 1)
    Physical Surface("Left", 6) = {1};
    Physical Surface("Right", 7) = {2};
    Physical Curve("Gamma2_right", 8) = {3};
  EndIf
EndIf
