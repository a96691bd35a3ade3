; TF5200 diagnosis, ID 20133 "Plane selection not allowed during active tool radius compensation.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250893707.html
; adapted: none.
; expect: error 20133
N10 G00 X0 Y0 Z0
N20 G41
N30 G19
N1000 M30
