%final.nc
( final_prog_file, P-CHAN-00252: before the main program's M30 )
N10 G00 Z100
N20 #MSG ["final.nc: retracted"]
N30 M17
