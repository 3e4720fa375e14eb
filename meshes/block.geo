// A block (0,1)×(0,1)×(0,0.5) for indentation: displacement prescribed on the top face, contact
// on the bottom face.
//
//   gmsh -3 block.geo -setnumber hexes 0 -setnumber lc 0.08 -format msh41 -o block_p1.msh
//   gmsh -3 block.geo -setnumber hexes 1 -setnumber n 8 -format msh41 -o block_q1_h8.msh
//
// Parameters (override with -setnumber):
//   hexes  1 = structured hexahedra (Q1), n × n × n/2 cubic cells of side h = 1/n,
//          0 = unstructured tetrahedra (P1) of characteristic length lc          (default 1)
//   n      cells per unit length with hexes 1 (n even)                            (default 8)
//   lc     characteristic length (target edge length) with hexes 0               (default 0.08)
// With hexes 1 the base z = 0 is a transfinite n × n grid extruded in n/2 layers.
//
// Physical groups (the tags a scene refers to):
//   Surface "Gamma1" 1  top face z = 0.5 (displacement prescribed)
//   Surface "Gamma2" 2  the four lateral faces x = 0, x = 1, y = 0, y = 1
//   Surface "Gamma3" 3  bottom face z = 0 (contact)
//   Volume  "Omega"  5  the body

DefineConstant[ hexes = 1, n = 8, lc = 0.08 ];

Lx = 1; Ly = 1; Lz = 0.5;

Point(1) = {0, 0, 0, lc};
Point(2) = {Lx, 0, 0, lc};
Point(3) = {Lx, Ly, 0, lc};
Point(4) = {0, Ly, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};  // counter-clockwise: normal +z, extruded along +z
Plane Surface(1) = {1};
If (hexes == 1)
  Transfinite Curve{1, 2, 3, 4} = n + 1;
  Transfinite Surface{1};
  Recombine Surface{1};
  ext[] = Extrude {0, 0, Lz} { Surface{1}; Layers{n / 2}; Recombine; };
Else
  ext[] = Extrude {0, 0, Lz} { Surface{1}; };
EndIf

e = 1e-6;
top[] = Surface In BoundingBox{-e, -e, Lz - e, Lx + e, Ly + e, Lz + e};
bottom[] = Surface In BoundingBox{-e, -e, -e, Lx + e, Ly + e, e};
x0[] = Surface In BoundingBox{-e, -e, -e, e, Ly + e, Lz + e};
x1[] = Surface In BoundingBox{Lx - e, -e, -e, Lx + e, Ly + e, Lz + e};
y0[] = Surface In BoundingBox{-e, -e, -e, Lx + e, e, Lz + e};
y1[] = Surface In BoundingBox{-e, Ly - e, -e, Lx + e, Ly + e, Lz + e};

Physical Surface("Gamma1", 1) = {top[]};
Physical Surface("Gamma2", 2) = {x0[], x1[], y0[], y1[]};
Physical Surface("Gamma3", 3) = {bottom[]};
Physical Volume("Omega", 5) = {ext[1]};

// The base z = 0 is meshed with normal +z (into the body) so that the extruded cells have positive
// orientation; reversing its surface mesh afterwards (the cells are not changed) makes the node
// order of every boundary facet give the outward normal, as on the other faces.
ReverseMesh Surface{1};
