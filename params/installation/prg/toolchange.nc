%toolchange.nc
( m6_prog_file, P-CHAN-00118: called for M6 )
N10 G00 Z150
N20 #MSG ["toolchange.nc: tool changed"]
N30 M17
