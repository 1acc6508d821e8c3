// The blast seed's concrete block (issue 17, docs/theory.md B1): quasi-2D, W x H x D, a borehole of
// radius R along z whose centre is 40 cm from the right face (x = W). Elements of about h_hole at
// the hole, growing by `growth` per metre of distance to h_far.
//   gmsh -3 -format msh22 block.geo -o block.msh                      (the seed's size: ~1,000 tets)
//   gmsh -3 -format msh22 -setnumber h_hole 0.01 block.geo -o fine.msh
W = 1.0; H = 1.0; D = 0.2;
R = 0.025; Xh = W - 0.4; Yh = H / 2;
If (!Exists(h_hole)) h_hole = 0.05; EndIf
If (!Exists(h_far)) h_far = 4 * h_hole; EndIf
If (!Exists(growth)) growth = 0.25; EndIf
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, W, H, D};
Cylinder(2) = {Xh, Yh, 0, 0, 0, D, R};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + %g * (Sqrt((x - %g)^2 + (y - %g)^2) - %g))", h_far, h_hole, growth, Xh, Yh, R);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm3D = 1;
Mesh.Optimize = 1;
