; TF5200 diagnosis, ID 20160 "Unknown internal M-function.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250945931.html
; adapted: the page's ":" line dropped; M30 appended.
; expect: error 20160
N10 G00 X0 Y0 Z0
N20 M1001
N30 M30
