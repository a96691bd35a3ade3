%contour-square
(G261 contouring: the corners of a 50 mm square blended within 0.05 mm; see docs/motion.md)
#CONTOUR MODE [DEV PATH_DEV=0.05]
G261
G1 X50 F3000
Y50
X0
Y0
G260
M30
