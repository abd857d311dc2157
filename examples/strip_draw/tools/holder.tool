# blank-holder: flat, inner edge R 2 mm; normals down
# written by examples/make_tools.py; units mm
ddpy-tool 1
name holder
description nagata
units mm
vertices 12
60 0 1
42.5 0 1
25 0 1
24 0 1.267949192
23.26794919 0 2
23 0 3
60 6 1
42.5 6 1
25 6 1
24 6 1.267949192
23.26794919 6 2
23 6 3
normals 6
0 0 -1
0 0 -1
0 0 -1
-0.5 0 -0.8660254038
-0.8660254038 0 -0.5
-1 0 0
faces 5
# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals
0 1 7 6 0 1 1 0 1
1 2 8 7 1 2 2 1 1
2 3 9 8 2 3 3 2 1
3 4 10 9 3 4 4 3 1
4 5 11 10 4 5 5 4 1
