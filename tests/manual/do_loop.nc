; TF5200 programming manual, "Verification of running condition at loop end ($DO), ($REPEAT)": $DO
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206946827.html
; adapted: F1000 added to N10 (the page relies on a feed programmed before it).
; expect: runs N50 11
; expect: end X=11 Y=0 Z=0
N10 X0 Y0 Z0 F1000
N20 P2=10 P1=0
N30 $DO
N40 P1=P1+1
N50 XP1
N60 $ENDDO P1 <= P2       (P1 is checked for TRUE at loop end)
N99 M30
