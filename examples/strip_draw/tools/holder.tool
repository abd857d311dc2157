# blank-holder: flat; normals down
# written by examples/make_tools.py; units mm
ddpy-tool 1
name holder
description nagata
units mm
vertices 6
60 0 1
42.5 0 1
25 0 1
60 6 1
42.5 6 1
25 6 1
normals 3
0 0 -1
0 0 -1
0 0 -1
faces 2
# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals
0 1 4 3 0 1 1 0 1
1 2 5 4 1 2 2 1 1
