// A box (0,1)² × (0,0.5) whose lower half is an extruded triangulation (prisms: what
// `Extrude … Layers{…}` of a triangulated surface makes) and whose upper half is meshed with
// tetrahedra on the same interface triangles: the mixed prism–tetrahedron mesh of issue 20.
//   gmsh -3 prism.geo -format msh41 -o prism_tet.msh
// Parameters (-setnumber): lc (default 0.25), layers (default 2).
// Physical groups: Surface "Gamma1" 1 (x = 0), "Gamma2" 2 (every other side and the top),
// "Gamma3" 3 (z = 0), Volume "Omega" 5.
If (!Exists(lc))
  lc = 0.25;
EndIf
If (!Exists(layers))
  layers = 2;
EndIf
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
low[] = Extrude {0, 0, 0.25} { Surface{1}; Layers{layers}; Recombine; };   // prisms
high[] = Extrude {0, 0, 0.25} { Surface{low[0]}; };              // tetrahedra
Physical Surface("Gamma1", 1) = {low[5], high[5]};
Physical Surface("Gamma2", 2) = {low[2], low[3], low[4], high[2], high[3], high[4], high[0]};
Physical Surface("Gamma3", 3) = {1};
Physical Volume("Omega", 5) = {low[1], high[1]};
