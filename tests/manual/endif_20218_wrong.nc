; TF5200 diagnosis, ID 20218 "Unexpected ENDIF. Does not match the current control block.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251141771.html
; adapted: the page's ":" line dropped.
; expect: error 20218
N10 G00 X0 Y0 Z0 P1=0
N20 G01 X100 F10000
N30 $ENDIF
N1000 M30
