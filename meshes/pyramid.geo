// A box (0,1)² × (0,0.5) whose upper half is structured hexahedra (a transfinite, recombined
// extrusion) and whose lower half is left to gmsh's tetrahedral mesher: gmsh then puts a pyramid
// on every interface quadrangle (the tetrahedra cannot match a quadrangle), by default, with no
// option: the mixed hexahedron–pyramid–tetrahedron mesh of issue 20.
//   gmsh -3 pyramid.geo -format msh41 -o pyramid_hex_tet.msh
// Parameters (-setnumber): n (default 6): n × n quadrangles on the interface z = 0.25 (so n²
// pyramids), n × n × 2 hexahedra above it, tetrahedra of size 1/n below it.
// Physical groups: Surface "Gamma1" 1 (x = 0, clamped), "Gamma2" 2 (x = 1, y = 0, y = 1 and the
// top z = 0.5, loaded), "Gamma3" 3 (the bottom z = 0, contact), Volume "Omega" 5 (both halves).
If (!Exists(n))
  n = 6;
EndIf
lc = 1 / n;
Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {1, 1, 0, lc};
Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2};  // y = 0
Line(2) = {2, 3};  // x = 1
Line(3) = {3, 4};  // y = 1
Line(4) = {4, 1};  // x = 0
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
// the lower half: tetrahedra (the extrusion without Layers only makes the geometry)
low[] = Extrude {0, 0, 0.25} { Surface{1}; };
// the interface z = 0.25 a structured grid of quadrangles, extruded into hexahedra
edges[] = Boundary{ Surface{low[0]}; };
Transfinite Curve{edges[]} = n + 1;
Transfinite Surface{low[0]};
Recombine Surface{low[0]};
high[] = Extrude {0, 0, 0.25} { Surface{low[0]}; Layers{2}; Recombine; };
Physical Surface("Gamma1", 1) = {low[5], high[5]};
Physical Surface("Gamma2", 2) = {low[2], low[3], low[4], high[2], high[3], high[4], high[0]};
Physical Surface("Gamma3", 3) = {1};
Physical Volume("Omega", 5) = {low[1], high[1]};
