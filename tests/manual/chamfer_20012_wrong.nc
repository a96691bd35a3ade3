; TF5200 diagnosis, ID 20012 "Radius or bevel is 0 in G301/302.": example 1 (chamfers), the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250528139.html
; adapted: none.
; expect: error 20012
N10   G00 X0 Y0 Z0
N20   G01 X10 F2000
N30   G301
N40   G01 Y10
N1000 M30
