; TF5200 programming manual, "Verification of running condition at loop start ($WHILE)"
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206940939.html
; adapted: a #MSG of P1 and M30 appended to show where the loop stops.
; expect: runs N110 67
; expect: msg "P1=-0.5"
N90 P1 = 100.0
N100 $WHILE P1 > 0.5      (P1 > 0.5 is checked at loop start)
N110 P1 = P1 - 1.5
N120 $ENDWHILE
N130 #MSG ["P1=%.1f", P1]
N140 M30
