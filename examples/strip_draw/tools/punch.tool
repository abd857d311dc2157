# punch: flat, corner R 5 mm, side wall; normals out
# written by examples/make_tools.py; units mm
ddpy-tool 1
name punch
description nagata
units mm
vertices 16
0 0 1
6 0 1
12 0 1
14.5 0 1.669872981
16.33012702 0 3.5
17 0 6
17 0 18
17 0 30
0 6 1
6 6 1
12 6 1
14.5 6 1.669872981
16.33012702 6 3.5
17 6 6
17 6 18
17 6 30
normals 8
0 0 -1
0 0 -1
0 0 -1
0.5 0 -0.8660254038
0.8660254038 0 -0.5
1 0 0
1 0 0
1 0 0
faces 7
# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals
8 9 1 0 0 1 1 0 1
9 10 2 1 1 2 2 1 1
10 11 3 2 2 3 3 2 1
11 12 4 3 3 4 4 3 1
12 13 5 4 4 5 5 4 1
13 14 6 5 5 6 6 5 1
14 15 7 6 6 7 7 6 1
