; TF5200 diagnosis, ID 20244 "Unexpected 'CONTINUE'. No valid/open control blocks.": the correct program, $CONTINUE in a $DO loop
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251254923.html
; adapted: the page's ":" lines dropped.
; expect: end X=0 Y=0 Z=0
; expect: runs N30 9
; expect: runs N1000 1
N10   G00 X0 Y0 Z0 P1=1
N20   $DO
N30     P1=P1+1
N40     $IF P1 == 2
N50       $CONTINUE
N60     $ENDIF
N100  $ENDDO P1 < 10
N1000 M30
