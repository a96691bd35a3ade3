; TF5200 diagnosis, ID 21500 "There are pending invalid control blocks at local subroutine end.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/254941067.html
; adapted: the page's remarks and ":" line dropped.
; expect: runs N100 0
; expect: runs N110 1
; expect: end X=0 Y=0
%L sub1
N10 G00 X0 Y0 Z0
N20 P1=0
N30 $IF P1 == 1
N40 Y100
N100 X100
N105 $ENDIF
N110 M29
% main
N010 X0 Y0 Z0
N020 LL sub1
N1000 M30
