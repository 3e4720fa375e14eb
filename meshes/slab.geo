// The paper's rectangle (0,2)×(0,1) extruded in z: the slab (0,2)×(0,1)×(0,Lz), Lz = layers·h.
//
//   gmsh -3 slab.geo -setnumber n 8 -setnumber layers 1 -format msh41 -o slab_q1_h8_z1.msh
//   gmsh -3 slab.geo -setnumber n 4 -setnumber layers 2 -setnumber hexes 0 -format msh41 -o slab_p1_h4.msh
//
// Parameters (override with -setnumber):
//   n       cells per unit length, h = 1/n                                   (default 8)
//   layers  cells along z, Lz = layers·h                                     (default 1)
//   hexes   1 = hexahedra (Q1, cubic h×h×h cells), 0 = tetrahedra (P1)      (default 1)
// The base z = 0 is meshed exactly as rectangle.geo meshes it (same points, curves, transfinite
// counts, recombination), then extruded in `layers` equal layers: every z layer has the nodes of
// rectangle.geo's mesh for the same n (with quads = hexes), node for node in (x, y).
// With hexes 0 each extruded prism is split by gmsh into 3 tetrahedra (conforming diagonals).
//
// Physical groups (the tags a scene refers to; the 2D tags of rectangle.geo where they exist):
//   Surface "Gamma1"     1  face x = 0 (clamped)
//   Surface "Gamma2"     2  faces x = 2 and y = 1 (loaded)
//   Surface "Gamma3"     3  face y = 0 (contact)
//   Surface "Gamma2_top" 4  face y = 1 only (its faces are also in Gamma2)
//   Surface "Sides"      6  faces z = 0 and z = Lz
//   Volume  "Omega"      5  the body

DefineConstant[ n = 8, layers = 1, hexes = 1 ];

Lx = 2; Ly = 1;
h = 1 / n;
Lz = layers * h;
nx = 2 * n;
ny = n;

Point(1) = {0, 0, 0};
Point(2) = {Lx, 0, 0};
Point(3) = {Lx, Ly, 0};
Point(4) = {0, Ly, 0};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right
Line(3) = {3, 4};   // top
Line(4) = {4, 1};   // left
Curve Loop(1) = {1, 2, 3, 4};  // counter-clockwise: surface normal +z, so the extruded
Plane Surface(1) = {1};        // elements have positive orientation
Transfinite Curve{1, 3} = nx + 1;
Transfinite Curve{2, 4} = ny + 1;
Transfinite Surface{1};
If (hexes == 1)
  Recombine Surface{1};
  ext[] = Extrude {0, 0, Lz} { Surface{1}; Layers{layers}; Recombine; };
Else
  ext[] = Extrude {0, 0, Lz} { Surface{1}; Layers{layers}; };
EndIf
// ext[0] = top z = Lz, ext[1] = the volume, ext[2..5] = the faces swept by curves 1..4. The
// groups below pick the faces by bounding box instead, which does not depend on that order.

e = 1e-6;
x0[] = Surface In BoundingBox{-e, -e, -e, e, Ly + e, Lz + e};
x2[] = Surface In BoundingBox{Lx - e, -e, -e, Lx + e, Ly + e, Lz + e};
y0[] = Surface In BoundingBox{-e, -e, -e, Lx + e, e, Lz + e};
y1[] = Surface In BoundingBox{-e, Ly - e, -e, Lx + e, Ly + e, Lz + e};
z0[] = Surface In BoundingBox{-e, -e, -e, Lx + e, Ly + e, e};
zL[] = Surface In BoundingBox{-e, -e, Lz - e, Lx + e, Ly + e, Lz + e};

Physical Surface("Gamma1", 1) = {x0[]};
Physical Surface("Gamma2", 2) = {x2[], y1[]};
Physical Surface("Gamma3", 3) = {y0[]};
Physical Surface("Gamma2_top", 4) = {y1[]};
Physical Surface("Sides", 6) = {z0[], zL[]};
Physical Volume("Omega", 5) = {ext[1]};

// The base z = 0 is meshed with normal +z (into the body) so that the extruded cells have positive
// orientation; reversing its surface mesh afterwards (the cells are not changed) makes the node
// order of every boundary facet give the outward normal, as on the other faces.
ReverseMesh Surface{1};
