; TF5200 programming manual, "Indirect parameters": P15 to P25 assigned 0.0
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206884875.html
; adapted: N100 presets P15 and P25 to 7, a #MSG of them and M30 appended to show the result.
; expect: msg "P15=0 P25=0 P1=21"
N100 P15 = 7  P25 = 7
N110 $FOR P1 = 10,20,1
N120 P[P1 + 5] = 0.0
N130 $ENDFOR
N140 #MSG ["P15=%.0f P25=%.0f P1=%.0f", P15, P25, P1]
N150 M30
