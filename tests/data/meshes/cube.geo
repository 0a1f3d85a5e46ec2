// Unit cube split at x = 0.5 into two volumes: regions "left" and "right"; node sets "bottom" (z = 0) and "top" (z = 1).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.5, 1, 1};
Box(2) = {0.5, 0, 0, 0.5, 1, 1};
Coherence;
Mesh.MeshSizeMin = 1; Mesh.MeshSizeMax = 1;
Physical Volume("left") = {1};
Physical Volume("right") = {2};
bottom() = Surface In BoundingBox{-0.1, -0.1, -0.1, 1.1, 1.1, 0.1};
top() = Surface In BoundingBox{-0.1, -0.1, 0.9, 1.1, 1.1, 1.1};
Physical Surface("bottom") = {bottom()};
Physical Surface("top") = {top()};
