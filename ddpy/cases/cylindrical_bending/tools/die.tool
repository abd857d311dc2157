# open die: inner wall, shoulder R 4 mm (4 Nagata patches), flat; normals up
# written by examples/make_tools.py; units mm
ddpy-tool 1
name die
description nagata
units mm
vertices 18
25.5 0 -20
25.5 0 -12
25.5 0 -4
25.80448187 0 -2.469266271
26.67157288 0 -1.171572875
27.96926627 0 -0.30448187
29.5 0 0
49.75 0 0
70 0 0
25.5 20 -20
25.5 20 -12
25.5 20 -4
25.80448187 20 -2.469266271
26.67157288 20 -1.171572875
27.96926627 20 -0.30448187
29.5 20 0
49.75 20 0
70 20 0
normals 9
-1 0 0
-1 0 0
-1 0 0
-0.9238795325 0 0.3826834324
-0.7071067812 0 0.7071067812
-0.3826834324 0 0.9238795325
0 0 1
0 0 1
0 0 1
faces 8
# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals
0 1 10 9 0 1 1 0 1
1 2 11 10 1 2 2 1 1
2 3 12 11 2 3 3 2 1
3 4 13 12 3 4 4 3 1
4 5 14 13 4 5 5 4 1
5 6 15 14 5 6 6 5 1
6 7 16 15 6 7 7 6 1
7 8 17 16 7 8 8 7 1
