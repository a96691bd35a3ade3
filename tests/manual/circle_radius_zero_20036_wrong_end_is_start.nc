; TF5200 diagnosis, ID 20036 "Radius of circle is 0.": the second wrong program (circle end point = start point)
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250610827.html
; adapted: none.
; expect: error 20036
N10 G00 X0 Y0 Z0
N20 G164 G02 X0 F1000 (circle end point = start point)
N1000 M30
