; TF5200 data streaming, "Jump to label": jump in the forward direction, run as a file program
; https://infosys.beckhoff.com/content/1033/tf5200_data_streaming/222579211.html
; adapted: the page's ":" line dropped; started as a main program (a file program may jump both ways, TF5200 programming manual, "The $GOTO statement").
; expect: end X=-40 Y=0 Z=0
; expect: blocks N01 N10 N40 N80 N90
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
