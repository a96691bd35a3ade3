%part.nc
( an example part: square pocket with a tool change, in G54 of nullp_d.lis; )
( D1 takes tool 1 of werkz_d.lis, its length lifts Z by 40 mm )
N10 G54 G00 X0 Y0 Z10
N20 T1 D1 M6
N30 G01 Z-5 F1000
N40 G01 X100 F3000
N50 G01 Y100
N60 G01 X0
N70 G01 Y0
N80 M30
