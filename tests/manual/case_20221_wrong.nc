; TF5200 diagnosis, ID 20221 "Unexpected CASE. Does not match the current control block.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251154827.html
; adapted: the page's ":" line dropped.
; expect: error 20221
N10 G00 X0 Y0 Z0 P1=47
N20 $CASE P1
N1000 M30
