; TF5200 diagnosis, ID 20036 "Radius of circle is 0.": the correct program, a half circle by its centre point
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250610827.html
; adapted: N1000 M30 of the wrong programs appended.
; expect: end X=10 Y=0 Z=0
; expect: blocks N10 N20 N1000
N10 G00 X0 Y0 Z0
N20 G164 G02 X10 I5 F1000
N1000 M30
