%init.nc
( start_init_prog_file, P-CHAN-00119: first action of every program )
N10 G90 G17
N20 #MSG ["init.nc: defaults set"]
N30 M17
