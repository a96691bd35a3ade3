; TF5200 diagnosis, ID 20034 "Programming of a full circle with radius specification not possible.": the correct program, a full circle by its centre point
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250602123.html
; adapted: N1000 M30 of the wrong program appended.
; expect: end X=0 Y=0 Z=0
; expect: blocks N10 N20 N1000
N10 G00 X0 Y0 Z0
N20 G02 I10 F1000
N1000 M30
