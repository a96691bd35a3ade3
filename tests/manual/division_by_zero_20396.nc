; TF5200 diagnosis, ID 20396 "Division by 0.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251507339.html
; adapted: the page's ":" line dropped; M30 appended.
; expect: error 20396
N10 G00 X0 Y0 Z0
N20 P2=10/COS[90]
N30 M30
