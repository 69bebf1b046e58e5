// The paper's half disc for the GetFEM peer comparison (benchmarks/peer_getfem.py): radius 1, centred at
// the origin, x >= 0; "axis" the symmetry line x = 0, "top_arc" where the traction acts, "bottom_arc" the
// contact part Γ3, "body" the triangles. The element size h is set from the command line:
//     gmsh half_disc.geo -2 -setnumber h 0.011 -format msh22 -o half_disc.msh
DefineConstant[ h = {0.011, Name "element size"} ];
Point(1) = {0, 0, 0, h};
Point(2) = {0, -1, 0, h};
Point(3) = {1, 0, 0, h};
Point(4) = {0, 1, 0, h};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Line(3) = {4, 2};
Curve Loop(1) = {1, 2, 3};
Plane Surface(1) = {1};
Physical Curve("bottom_arc") = {1};
Physical Curve("top_arc") = {2};
Physical Curve("axis") = {3};
Physical Surface("body") = {1};
