; TF5200 diagnosis, ID 20116 "Double-programmed zero point offsets.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250824075.html
; adapted: the page's ":" line dropped.
; expect: error 20116
N10 G00 X0 Y0 Z0
N20 G53 X10 Y10 G54
N1000 M30
