(an error in the middle: blocks before it run, the error names the line and column)
N10 G01 X10 F3000
N20 Y10
N30 $IF P1 ==
N40 X20
M30
