; TF5200 diagnosis, ID 20216 "Unexpected ELSEIF. Does not match the current control block.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251133067.html
; adapted: the page's ":" line dropped.
; expect: runs N10 0
; expect: runs N30 0
; expect: end X=0
N01   P1=0
N05   $IF P1==1
N10     G00 X0 Y0 Z0
N20   $ELSEIF P1==2
N30     G00 X100 Y0 Z0
N40   $ENDIF
N1000 M30
