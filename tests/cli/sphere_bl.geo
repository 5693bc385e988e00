// A tet-dominant boundary-layer mesh around a sphere: 4 layers extruded along the surface normals (gmsh's
// boundary-layer extrusion), hexahedra over the recombined half of the sphere, prisms over the other,
// pyramids where the tets meet the quads, tets out to a box.
lc = 0.12;
r = 0.5;
Point(1) = {0, 0, 0, lc};
Point(2) = {r, 0, 0, lc}; Point(3) = {0, r, 0, lc}; Point(4) = {-r, 0, 0, lc};
Point(5) = {0, -r, 0, lc}; Point(6) = {0, 0, -r, lc}; Point(7) = {0, 0, r, lc};
Circle(1) = {2, 1, 3}; Circle(2) = {3, 1, 4}; Circle(3) = {4, 1, 5}; Circle(4) = {5, 1, 2};
Circle(5) = {3, 1, 6}; Circle(6) = {6, 1, 5}; Circle(7) = {5, 1, 7}; Circle(8) = {7, 1, 3};
Circle(9) = {2, 1, 7}; Circle(10) = {7, 1, 4}; Circle(11) = {4, 1, 6}; Circle(12) = {6, 1, 2};
Curve Loop(13) = {2, 8, -10}; Surface(14) = {13};
Curve Loop(15) = {10, 3, 7}; Surface(16) = {15};
Curve Loop(17) = {-8, -9, 1}; Surface(18) = {17};
Curve Loop(19) = {-11, -2, 5}; Surface(20) = {19};
Curve Loop(21) = {-5, -12, -1}; Surface(22) = {21};
Curve Loop(23) = {-3, 11, 6}; Surface(24) = {23};
Curve Loop(25) = {-7, 4, 9}; Surface(26) = {25};
Curve Loop(27) = {-4, 12, -6}; Surface(28) = {27};
Recombine Surface {14, 16, 18, 26};
bl[] = Extrude { Surface{14, 16, 18, 20, 22, 24, 26, 28}; Layers{4, 0.08}; Recombine; };
b = 1.5;
Point(101) = {-b, -b, -b, 0.3}; Point(102) = {b, -b, -b, 0.3}; Point(103) = {b, b, -b, 0.3}; Point(104) = {-b, b, -b, 0.3};
Line(101) = {101, 102}; Line(102) = {102, 103}; Line(103) = {103, 104}; Line(104) = {104, 101};
Curve Loop(101) = {101, 102, 103, 104}; Plane Surface(101) = {101};
box[] = Extrude {0, 0, 2 * b} { Surface{101}; };
Delete { Volume{box[1]}; }
Surface Loop(201) = {101, box[0], box[2], box[3], box[4], box[5]};
Surface Loop(202) = {bl[0], bl[5], bl[10], bl[15], bl[20], bl[25], bl[30], bl[35]};
Volume(301) = {201, 202};
