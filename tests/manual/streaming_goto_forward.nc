; TF5200 data streaming, "Jump to label": jump in the forward direction
; https://infosys.beckhoff.com/content/1033/tf5200_data_streaming/222579211.html
; run: stream
; adapted: the page's ":" line dropped; the three data packages are one stream.
; expect: end X=-40 Y=0 Z=0
; expect: blocks N01 N10 N40 N80 N90
; expect: runs N30 0
; expect: runs N60 0
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
