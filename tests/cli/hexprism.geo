// Hexahedra and prisms sharing quad faces, with a curved side: a quarter annulus of quads (transfinite,
// recombined) beside a triangle-meshed square, both extruded in layers.
Point(1) = {1, 0, 0, 0.3}; Point(2) = {2, 0, 0, 0.3}; Point(3) = {0, 2, 0, 0.3}; Point(4) = {0, 1, 0, 0.3};
Point(5) = {0, 0, 0, 0.3}; Point(6) = {2, -1, 0, 0.3}; Point(7) = {1, -1, 0, 0.3};
Line(1) = {1, 2}; Circle(2) = {2, 5, 3}; Line(3) = {3, 4}; Circle(4) = {4, 5, 1};
Line(5) = {2, 6}; Line(6) = {6, 7}; Line(7) = {7, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 3} = 3; Transfinite Curve{2, 4} = 5;
Transfinite Surface{1}; Recombine Surface{1};
Curve Loop(2) = {1, 5, 6, 7}; Plane Surface(2) = {2};
Extrude {0, 0, 0.5} { Surface{1, 2}; Layers{2}; Recombine; }
