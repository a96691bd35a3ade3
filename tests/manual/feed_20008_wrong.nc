; TF5200 diagnosis, ID 20008 "Feed rate in motion block is 0.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250515083.html
; adapted: M30 appended.
; expect: error 20008
N10 G00 X0 Y0 Z0
N20 G01 X10
N30 M30
