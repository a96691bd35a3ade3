; TF5200 diagnosis, ID 20574 "Division by 0." (combined assignment /=): the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251868555.html
; adapted: the page's ":" lines dropped.
; expect: error 20574
N10 P1=0
N500 P2/=P1
N1000 M30
