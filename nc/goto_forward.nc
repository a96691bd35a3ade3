(seed 003 §2.3.6 "Jump in the forward direction"; blank lines separate the packets)
N01 G01 X0 Y0 Z0 F1000
N10 G01 X20
N20 $GOTO N40
N30 G01 Z40
N40: G01 X40
N50 $GOTO N80

N60 G01 Y20
N70 G01 Y40

N80: G01 X-20
N90 G01 X-40
M30
