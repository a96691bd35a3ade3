(nested local and global subroutines, parameters and a $GOTO back)
%L INNER
G91 G01 X[P5] F4000
G90
M17
%L OUTER
P5 = P5 + 1
LL INNER
LL INNER
M17
%main
N10 G90 G01 X0 Y0 F5000
P5 = 1
P6 = 0
N20: LL OUTER
P6 = P6 + 1
$IF P6 < 4 $GOTO N20
N30 G01 Y[P5]
M30
