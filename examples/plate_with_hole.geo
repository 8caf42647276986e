// A plate with a central hole, for examples/custom_part.py: 200 mm long (x), 100 mm wide (y),
// 2 mm thick (z), hole 20 mm diameter at the centre.  Only the quarter y >= 0, z >= 0 is built:
// the planes y = 0 and z = 0 are planes of symmetry.  Named surfaces (physical groups) are
// what loads and supports attach to: held (x = 0), loaded (x = 200), hole, ysym, zsym.
SetFactory("OpenCASCADE");
L = 200; W = 100; t = 2; r = 10; e = 1e-3;
Box(1) = {0, 0, 0, L, W / 2, t / 2};
Cylinder(2) = {L / 2, 0, -1, 0, 0, t / 2 + 2, r};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Physical Surface("held") = Surface In BoundingBox{-e, -e, -e, e, W / 2 + e, t / 2 + e};
Physical Surface("loaded") = Surface In BoundingBox{L - e, -e, -e, L + e, W / 2 + e, t / 2 + e};
Physical Surface("hole") = Surface In BoundingBox{L / 2 - r - e, -e, -e, L / 2 + r + e, r + e, t / 2 + e};
Physical Surface("ysym") = Surface In BoundingBox{-e, -e, -e, L + e, e, t / 2 + e};
Physical Surface("zsym") = Surface In BoundingBox{-e, -e, -e, L + e, W / 2 + e, e};
Physical Volume("plate") = {3};
