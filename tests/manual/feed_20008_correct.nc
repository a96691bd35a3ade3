; TF5200 diagnosis, ID 20008 "Feed rate in motion block is 0.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250515083.html
; adapted: M30 appended.
; expect: end X=10 Y=0 Z=0
N10 G00 X0 Y0 Z0
N20 G01 X10 F1000
N30 M30
