(global subroutine called by subroutine_call.nc: a 40 x 40 square, then back)
N10 G01 X240 Y0 F1000
N20 Y40
N30 X200
N40 Y0
N50 M17
