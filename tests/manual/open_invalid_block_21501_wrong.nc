; TF5200 diagnosis, ID 21501 "There are pending invalid control blocks at main program end.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/254945419.html
; adapted: the page's "? $ENDIF ... missing" remark dropped.
; expect: error 21501
% main
N10 G00 X0 Y0 Z0
N20 P1=0
N30 $IF P1 == 1
N40 Y100
N100 X100
N150 M30
