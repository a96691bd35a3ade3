; TF5200 diagnosis, ID 20014 "Dwell time is not programmed with the coordinate of first axis.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250536843.html
; expect: error 20014
N10 G00 X0 Y0 Z0
N20 G04 Y2
N1000 M30
