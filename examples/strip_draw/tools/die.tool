# die: wall, shoulder R 5 mm, flange; normals up
# written by examples/make_tools.py; units mm
ddpy-tool 1
name die
description nagata
units mm
vertices 16
20 0 -20
20 0 -12.5
20 0 -5
20.66987298 0 -2.5
22.5 0 -0.6698729811
25 0 0
42.5 0 0
60 0 0
20 6 -20
20 6 -12.5
20 6 -5
20.66987298 6 -2.5
22.5 6 -0.6698729811
25 6 0
42.5 6 0
60 6 0
normals 8
-1 0 0
-1 0 0
-1 0 0
-0.8660254038 0 0.5
-0.5 0 0.8660254038
0 0 1
0 0 1
0 0 1
faces 7
# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals
0 1 9 8 0 1 1 0 1
1 2 10 9 1 2 2 1 1
2 3 11 10 2 3 3 2 1
3 4 12 11 3 4 4 3 1
4 5 13 12 4 5 5 4 1
5 6 14 13 5 6 6 5 1
6 7 15 14 6 7 7 6 1
