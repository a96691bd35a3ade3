; TF5200 diagnosis, ID 20241 "After 'ENDDO' only the condition is permissible.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251241867.html
; adapted: the page's ":" lines dropped.
; expect: error 20241
N10 G00 X0 Y0 Z0
N20 P2=10
N30 $DO
N40 $ENDDO P2 >= 10 G01 X100 F1000
N1000 M30
