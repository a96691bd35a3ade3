; TF5200 diagnosis, ID 20375 "There are valid open control blocks at program end.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251459467.html
; adapted: the page's ":" lines dropped.
; expect: end X=100 Y=100 Z=0
; expect: runs N60 0
N10 G00 X0 Y0 Z0
N20 P1=1 P2=2
N30 $IF P1 == 1
N40 Y100
N50 $IF P2==4
N60 Z200
N70 $ENDIF
N80 $ENDIF
N100 X100
N1000 M30
