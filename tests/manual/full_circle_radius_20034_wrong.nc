; TF5200 diagnosis, ID 20034 "Programming of a full circle with radius specification not possible.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250602123.html
; adapted: none.
; expect: error 20034
N10 G00 X0 Y0 Z0
N20 G02 X0 Y0 R10 F1000
N1000 M30
