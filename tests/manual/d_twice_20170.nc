; TF5200 diagnosis, ID 20170 "Double-programmed D-function.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250985099.html
; adapted: the page's ":" line dropped.
; expect: error 20170
N10   G00 X0 Y0 Z0
N20   D1 D2
N1000 M30
