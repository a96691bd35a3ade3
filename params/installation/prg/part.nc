%part.nc
( an example part: square pocket with a tool change )
N10 G00 X0 Y0 Z10
N20 T1 D1 M6
N30 G01 Z-5 F1000
N40 G01 X100 F3000
N50 G01 Y100
N60 G01 X0
N70 G01 Y0
N80 M30
