// A slab of the quarter thick-walled cylinder: ring.geo's quarter annulus 1 <= r <= 2,
// 0 <= θ <= π/2, extruded in z by Lz = 0.5. Structured: n cells across the wall, 2n along the
// quarter arc (as ring.geo), max(1, floor(n/2)) layers along z.
//   gmsh -3 cylinder.geo -setnumber n 4 -setnumber kind 1 -order 2 -format msh41 -o cylinder_hex27_n4.msh
// Parameters (-setnumber):
//   n     cells across the wall (default 4)
//   kind  0 = tetrahedra (triangulated base extruded without Recombine: gmsh splits each prism
//             into 3 tetrahedra),
//         1 = hexahedra (recombined base, recombined extrusion),
//         2 = prisms (triangulated base, recombined extrusion)            (default 1)
// With -order 2 the high-order nodes are put on the geometry (the cylinders r = 1, r = 2 and the
// arcs), i.e. the boundary is curved (isoparametric); add
// -setnumber Mesh.SecondOrderIncomplete 1 for the serendipity 20-node hexahedra / 15-node prisms.
// Physical groups:
//   Surface "Inner"  1  r = 1, the pressurised bore
//   Surface "Outer"  2  r = 2, traction-free
//   Surface "SymX"   3  x = 0 (symmetry: u_x = 0)
//   Surface "SymY"   4  y = 0 (symmetry: u_y = 0)
//   Surface "Bottom" 6  z = 0
//   Surface "Top"    7  z = Lz = 0.5
//   Volume  "Omega"  5  the body
If (!Exists(n))
  n = 4;
EndIf
If (!Exists(kind))
  kind = 1;
EndIf
a = 1.0;
b = 2.0;
Lz = 0.5;
layers = (n >= 2) ? Floor(n / 2) : 1;
Point(1) = {0, 0, 0};
Point(2) = {a, 0, 0};
Point(3) = {b, 0, 0};
Point(4) = {0, b, 0};
Point(5) = {0, a, 0};
Line(1) = {2, 3};          // y = 0
Circle(2) = {3, 1, 4};     // r = b
Line(3) = {4, 5};          // x = 0
Circle(4) = {5, 1, 2};     // r = a
Curve Loop(1) = {1, 2, 3, 4};  // counter-clockwise: surface normal +z, so the extruded cells
Plane Surface(1) = {1};        // have positive orientation
Transfinite Curve{1, 3} = n + 1;
Transfinite Curve{2, 4} = 2 * n + 1;
Transfinite Surface{1};
If (kind == 1)
  Recombine Surface{1};
EndIf
If (kind == 0)
  ext[] = Extrude {0, 0, Lz} { Surface{1}; Layers{layers}; };
Else
  ext[] = Extrude {0, 0, Lz} { Surface{1}; Layers{layers}; Recombine; };
EndIf
// ext[0] = the top z = Lz, ext[1] = the volume, ext[2..5] = the faces swept by curves 1..4
// (y = 0, r = b, x = 0, r = a).
Physical Surface("Inner", 1) = {ext[5]};
Physical Surface("Outer", 2) = {ext[3]};
Physical Surface("SymX", 3) = {ext[4]};
Physical Surface("SymY", 4) = {ext[2]};
Physical Surface("Bottom", 6) = {1};
Physical Surface("Top", 7) = {ext[0]};
Physical Volume("Omega", 5) = {ext[1]};
// The base z = 0 is meshed with normal +z (into the body) so that the extruded cells are
// positively oriented; reversing its surface mesh afterwards (the cells are not changed) makes the
// node order of every boundary facet give the outward normal, as on the other faces (as slab.geo).
ReverseMesh Surface{1};
