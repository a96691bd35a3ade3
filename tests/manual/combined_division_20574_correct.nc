; TF5200 diagnosis, ID 20574 "Division by 0." (combined assignment /=): the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251868555.html
; adapted: the page's ":" lines dropped.
; expect: runs N500 0
; expect: runs N1000 1
N10 P1=0
N495 $IF P1 != 0
N500 P2/=P1
N505 $ENDIF
N1000 M30
