// Regenerate the mesh: gmsh -3 tests/data/grain_spheroid.geo -o tests/data/grain_spheroid.msh -format msh41
// The seed's grain: a prolate spheroid 1.27 x 0.52 mm (units: m)
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Dilate {{0, 0, 0}, {0.635e-3, 0.26e-3, 0.26e-3}} { Volume{1}; }
Mesh.CharacteristicLengthMax = 0.3e-3;
