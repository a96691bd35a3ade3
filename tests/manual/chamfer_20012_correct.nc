; TF5200 diagnosis, ID 20012 "Radius or bevel is 0 in G301/302.": example 1 (chamfers), the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250528139.html
; adapted: none.
; expect: end X=10 Y=10 Z=0
N10   G00 X0 Y0 Z0
N20   G01 X10 F2000
N30   G301 I5
N40   G01 Y10
N1000 M30
